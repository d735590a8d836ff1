"""`granplate bench`: the command line of the benchmark harness (granplate.bench.harness)."""

from __future__ import annotations

from granplate.bench import write_report
from granplate.setup.law_registry import TANGENTIAL_LAW_REGISTRY


def _cmd_study(args) -> int:
    import sys

    from granplate.bench import study

    for name, value in (("--designs", args.designs), ("--workers", args.workers)):
        if value is not None and value < 1:
            print(f"granplate: error: {name} = {value}: must be >= 1", file=sys.stderr)
            return 2
    report = study.run(
        args.designs or study.DEFAULT_DESIGNS,
        workers=args.workers,
        scheduler=args.scheduler,
        t_end=args.t_end,
        log=lambda line: print(line, file=sys.stderr),
    )
    print(study.format_report(report))
    write_report(args, report)
    return 0


def _cmd_bench(args) -> int:
    if getattr(args, "startup", False):
        from granplate.bench import startup

        return int(startup.main(args))
    if getattr(args, "scaling", False):
        from granplate.bench import scaling

        return int(scaling.main(args))
    if getattr(args, "friction", False):
        from granplate.bench import friction

        return int(friction.main(args))
    if getattr(args, "study", False):
        return _cmd_study(args)
    if getattr(args, "pour", False):
        from granplate.bench import pour

        return int(pour.main(args))
    if getattr(args, "twins", False):
        from granplate.bench import twins

        return int(twins.main(args))
    if getattr(args, "plastic", False):
        from granplate.bench import plastic

        return int(plastic.main(args))
    if getattr(args, "solid", False) and getattr(args, "coupled", False) and getattr(args, "profile", False):
        from granplate.bench import solid_profile

        return int(solid_profile.main(args))
    if getattr(args, "solid", False) and getattr(args, "coupled", False):
        from granplate.bench import solid_coupled

        return int(solid_coupled.main(args))
    if getattr(args, "solid", False):
        from granplate.bench import solid

        return int(solid.main(args))
    if getattr(args, "plates", False):
        return _cmd_plates(args)
    from granplate.bench import harness

    return int(harness.main(args))


#: `--plates`' benchmark module by the dimension's name (model.dimension): the plane's
#: plate meshes, or with --dimension 3 the 3D solid's rows (as --solid)
PLATE_BENCHES = {"plane": "plates", "space": "solid"}


def _cmd_plates(args) -> int:
    import importlib

    from granplate.model.dimension import DIMENSIONS, PLANE

    dim = DIMENSIONS.get(getattr(args, "dimension", None), PLANE)
    return int(importlib.import_module(f"granplate.bench.{PLATE_BENCHES[dim.name]}").main(args))


def register(subparsers) -> None:
    """The `granplate bench` subcommand: the presets' table, and each other table's options."""
    b = subparsers.add_parser("bench", help="benchmark speed and accuracy of every scheme")
    preset_options(b)
    plate_and_solid_options(b)
    scaling_options(b)
    more_tables_options(b)
    study_options(b)
    b.set_defaults(func=_cmd_bench)


def preset_options(b) -> None:
    """The presets' table: quick mode, JSON, cases, repeats, simulated time."""
    b.add_argument("--quick", action="store_true", help="a subset of presets, shortened, 1 repeat (under a minute)")
    b.add_argument("--json", metavar="FILE", help="write the report as JSON to FILE")
    b.add_argument("--cases", help="comma-separated preset names (default: all six; quick: a subset)")
    b.add_argument(
        "--repeats",
        type=int,
        default=None,
        help="timed repeats per case; the median is reported (default 3, quick 1; with --scaling --dimension 3: "
        "each row's run timed that many times in its process, granplate's and LAMMPS's, default 1)",
    )
    b.add_argument(
        "--t-end",
        dest="t_end",
        type=float,
        default=None,
        help="simulated time [s] for every case (overrides the mode's)",
    )


def plate_and_solid_options(b) -> None:
    """--plates (the plate-scaling table) and --solid (the 3D solid's set-up, coupled runs
    and their profile), with their meshes and modes."""
    b.add_argument(
        "--plates",
        action="store_true",
        help="instead: the plate-scaling table (set-up time, peak memory, steel-r1 run "
        "time per plate mesh, each in a fresh process with a cold plate cache)",
    )
    b.add_argument(
        "--solid",
        action="store_true",
        help="instead: the 3D solid's set-up time and peak memory (a clamped 100 x 100 x 5 mm steel "
        "plate, modes below 100 kHz, with and without the top face's residual compliance), the "
        "cost per dof of hex20, hex27, tet10, and each element's first clamped frequency "
        "against Leissa (--quick: the element tables only)",
    )
    b.add_argument(
        "--coupled",
        action="store_true",
        help="with --solid: the coupled runs instead (a 300-sphere FCC protector pressed on the "
        "clamped plate, 1 ms of velocity Verlet): set-up uncached and cached, loop, us per "
        "step and its growth with the dofs, the modes and the spheres in touch; the plate's "
        "peak energy share and peak contact force per cut-off, protector and sphere drop "
        "(--quick: a smoke run, 0.1 ms, no finest mesh, the drop's cut-offs against 100 kHz; "
        "--repeats: the timings' median)",
    )
    b.add_argument(
        "--profile",
        action="store_true",
        help="with --solid --coupled: where the body's contact pass spends a step (closest point, "
        "surface motion, force spread, residual matrix, its solve), timed per sub-pass on the "
        "protector on each mesh",
    )
    b.add_argument("--meshes", help="with --plates: comma-separated NXxNY (default 4x40,8x80,16x160,32x320)")
    b.add_argument(
        "--modes",
        dest="plate_modes",
        choices=("auto", "all", "truncated"),
        default=None,
        help="with --plates: plate.modes of every mesh (default auto)",
    )


def scaling_options(b) -> None:
    """--scaling (the granule-scaling table): dimension, sizes, scheme, threads, LAMMPS."""
    b.add_argument(
        "--scaling",
        action="store_true",
        help="instead: the granule-scaling table (10 to 10,000 granules of a launched hexagonal "
        "packing, with and without friction: set-up, steps, loop time, us per contact and "
        "step, peak memory; LAMMPS's time to the same accuracy where it is installed)",
    )
    b.add_argument(
        "--dimension",
        type=int,
        default=None,
        help="with --scaling: 2 (default: the plane, a hexagonal packing) or 3 (space: a launched "
        "FCC packing of 12 to 10,192 spheres, LAMMPS's 3D run side by side); with --plates 3: "
        "the 3D solid's rows, as --solid",
    )
    b.add_argument(
        "--sizes",
        help="with --scaling: comma-separated COLUMNSxROWS (default 4x3,8x13,32x32,56x54,100x100); "
        "with --dimension 3 FCC cells NXxNYxNZ (default 3x1x1,3x3x3,6x6x7,9x9x9,14x14x13); "
        "with --pour: comma-separated sphere counts (default 1000,10000)",
    )
    b.add_argument(
        "--scheme",
        default=None,
        help="with --scaling: solver.scheme of granplate's runs, any registered scheme (default implicit)",
    )
    b.add_argument(
        "--threads",
        help="with --scaling --dimension 3: comma-separated thread counts, a row each (solver.threads; "
        "LAMMPS on as many MPI processes); default 1 and every core for --scheme verlet, else 1; "
        "with --pour: the settling's threads (default every core)",
    )
    b.add_argument(
        "--mu",
        help="with --scaling --dimension 3: comma-separated friction coefficients, rows each "
        "(default 0,0.099); a size above 100,000 spheres runs without the reference, and "
        "LAMMPS runs it at our step under --scheme verlet (frictionless, or --friction-law mindlin)",
    )
    b.add_argument(
        "--friction-law",
        dest="friction_law",
        choices=tuple(TANGENTIAL_LAW_REGISTRY),
        default=None,
        help="with --scaling --dimension 3: contact.tangential_law of the rows with friction "
        "(default tanh, the paper's; mindlin runs under --scheme verlet, beside LAMMPS's same law at our step)",
    )
    b.add_argument(
        "--no-lammps",
        dest="no_lammps",
        action="store_true",
        help="with --scaling or --friction: leave LAMMPS out even where it is installed",
    )


def more_tables_options(b) -> None:
    """--startup, --friction, --plastic and --twins: a run's start, split friction, the
    elastic-plastic law's cost and the 3D twins."""
    b.add_argument(
        "--startup",
        action="store_true",
        help="instead: a run's start, from its process's start to its first step, and its peak memory "
        "(a launched frictionless FCC block in a box, velocity Verlet): two spheres, then "
        "10,192 (--sizes NXxNYxNZ cells) as [[granules]] tables and as each granules_file "
        "format (--formats toml,csv,npz,nc); medians of --repeats fresh processes (default 3)",
    )
    b.add_argument("--formats", help="with --startup: comma-separated toml,csv,npz,nc (default all)")
    b.add_argument(
        "--pour",
        action="store_true",
        help="instead: poured packings in space dropped one by one and settled at the real "
        "stiffness (1,000 and 10,000 spheres): deposition, wall and CPU time, steps, what it reached",
    )
    b.add_argument(
        "--friction",
        action="store_true",
        help="instead: steps and time with the granules' friction split off or inside RK4 "
        "(a 990-granule packing, ptfe-r05 under q0 = 1e7 N/m), and the packing side by "
        "side with LAMMPS where it is installed (loop time, us per contact and step, error)",
    )
    b.add_argument(
        "--plastic",
        action="store_true",
        help="instead: the loop time per step of the elastic-plastic normal law against Hertz's "
        "(a 990-granule packing, ptfe-r05 and steel-r1 under both schemes)",
    )
    b.add_argument(
        "--twins",
        action="store_true",
        help="instead: each paper case beside its 3D twin (3d-NAME): E_shock and the plate's peak "
        "share against the thin-limit targets, the twin's residual and step, the wall time of "
        "both (set-up and loop) and of the whole simulate call, medians of --repeats, timed "
        "alternately in one process (--cases, --t-end as for the presets)",
    )


def study_options(b) -> None:
    """--study: a design study's throughput on Dask."""
    b.add_argument(
        "--study",
        action="store_true",
        help="instead: the throughput of a design study on Dask (a ptfe-r05 sweep, 2 ms "
        "each): core-seconds per design all included, overhead vs the loop",
    )
    b.add_argument("--designs", type=int, default=None, help="with --study: number of designs (default 200)")
    b.add_argument(
        "--workers", type=int, default=None, help="with --study: local Dask workers (default: the number of cores)"
    )
    b.add_argument(
        "--scheduler", metavar="ADDRESS", default=None, help="with --study: an existing Dask cluster instead"
    )
