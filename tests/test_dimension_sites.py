r"""The dimension lives in one place (docs/architecture.md, "Where the dimension lives"):
the explicit tests of the dimension outside `setup`, counted line by line with PATTERN over
the package's source, stay at most LIMIT; and what each dimension names agrees with the
loop's state columns and the Dataset's variables.

The count, as a shell command from the repository's root (GNU grep; the same lines):

    grep -rnE '\bdim(ension)?"?(, ?[23]\))? ?[!=]= ?"?[23]\b|dimension_of\([^)]*\) ?[!=]=|\bis_space\b|\.ndim ?== ?3|"(z|vz|omega_[xyz]|KE_depth)" (not )?in\b|shape\[[0-9]\] ?[!=]= ?[69]\b|_module_of\([^)]*\) is\b|== ?"Granular3?"|dimension not in \(' \
        granplate --include=*.py | grep -v '^granplate/setup/'
"""

from __future__ import annotations

import re
from pathlib import Path

import granplate

PACKAGE = Path(granplate.__file__).parent

#: an explicit test of the dimension: its number compared (a scenario's, a result's, a
#: variable called dim), a result's or a scenario's `is_space`, a variable of one dimension
#: tested for, the state's column count compared with the plane's or space's, the solver's
#: granular kernels or arrays class tested by identity or name
PATTERN = re.compile(
    r"""\bdim(ension)?"?(, ?[23]\))? ?[!=]= ?"?[23]\b"""
    r"""|dimension_of\([^)]*\) ?[!=]="""
    r"""|\bis_space\b"""
    r"""|\.ndim ?== ?3"""
    r"""|"(z|vz|omega_[xyz]|KE_depth)" (not )?in\b"""
    r"""|shape\[[0-9]\] ?[!=]= ?[69]\b"""
    r"""|_module_of\([^)]*\) is\b"""
    r"""|== ?"Granular3?\""""
    r"""|dimension not in \("""
)

#: the most sites allowed: the Dataset's dimension of a file written before its attribute
#: (results/dataset.py) and the LAMMPS adapter's refusal of a 2D scenario in its 3D map
#: (verification/lammps.py)
LIMIT = 2


def sites(root: Path = PACKAGE) -> list[str]:
    """'path:line: text' of every line outside setup/ that PATTERN finds."""
    found = []
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(root.parent).as_posix()
        if rel.startswith("granplate/setup/"):
            continue
        for k, line in enumerate(path.read_text().splitlines(), 1):
            if PATTERN.search(line):
                found.append(f"{rel}:{k}: {line.strip()}")
    return found


def test_pattern_finds_every_form_of_the_test():
    """The pattern finds each way the dimension was tested before it lived in one place
    (lines of the package before), and none of the ways it is asked now."""
    tested = [
        "    if s.dimension == 3:",
        '    if getattr(s, "dimension", 2) == 3:',
        "    if dimension_of(ds) == 2 and ds.sizes.get('field_time', 0) == 0:",
        "        if space.is_space(ds):",
        '    return int(d) if d is not None else 3 if "z" in ds.variables else 2',
        '    if dimension_of(ds) == 3 and "KE_depth" in ds:',
        "    space = y.shape[1] == 9",
        '        if name == "KE_depth" and y.shape[2] != 9:',
        "    if _module_of(g) is space:",
        '        dimension = 3 if g.instance_class.__name__ == "Granular3" else 2',
        '    where = "in space" if dim == 3 else "in the plane"',
        "    if dimension not in (2, 3):",
        '    if dimension == "3":',
    ]
    asked = [
        "    return precompressed(MODEL_BUILDERS[of_number(s.dimension).name](s))",
        "    for name in dimension_spec(ds).depth_energies:",
        "    dimension = getattr(args, 'dimension', None) or 2",
        "    kin = np.zeros((len(pairs), 3))",
    ]
    assert [t for t in tested if not PATTERN.search(t)] == []
    assert [t for t in asked if PATTERN.search(t)] == []


def test_dimension_tests_outside_setup_at_most_limit():
    """At most LIMIT explicit tests of the dimension outside setup (the rest ask
    model.dimension or a layer's per-dimension table)."""
    found = sites()
    assert len(found) <= LIMIT, "explicit dimension tests outside setup:\n" + "\n".join(found)


def test_dimensions_name_the_loop_state_and_the_dataset():
    """Each dimension's state variables are the loop's state columns (model.inputs), its
    arrays class is the loop's, and its names are the Dataset's documented variables."""
    from granplate.model import inputs
    from granplate.model.dimension import DIMENSIONS, of_arrays, of_number, of_state
    from granplate.results.dataset import STATE_VARIABLES, VARIABLES

    assert sorted(DIMENSIONS) == sorted(inputs.STATE_COLUMNS)
    for n, d in DIMENSIONS.items():
        assert d.state_columns == inputs.STATE_COLUMNS[n]
        assert of_number(n) is d and of_state(d.state_columns) is d
        assert of_arrays(getattr(inputs, d.arrays)) is d
        assert STATE_VARIABLES[d.state_columns] == d.state_variables
        assert set(d.variables) <= set(VARIABLES)
        assert len(d.positions) == len(d.velocities) == d.n
    plane, space = DIMENSIONS[2], DIMENSIONS[3]
    assert plane.foreign("KE_depth") and plane.foreign("z") and not plane.foreign("x")
    assert space.foreign("theta") and not space.foreign("KE_depth") and not space.foreign("E_shock")
    assert plane.spin((2.5,)) == 2.5 and space.spin([1.0, 2.0, 3.0]) == (1.0, 2.0, 3.0)
