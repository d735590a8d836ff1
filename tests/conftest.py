"""Shared fixtures: an isolated plate cache per session, small scenario builders."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

from granplate.setup.scenario import Contact, Granule, Load, Scenario, TimeSettings, Wall


@pytest.fixture(autouse=True, scope="session")
def _plate_cache(tmp_path_factory):
    import os

    os.environ.setdefault("GRANPLATE_CACHE", str(tmp_path_factory.mktemp("plate-cache")))
    # each test compiles only the kernels it runs: the workers share numba's cache, and one
    # `granplate run` compiling every scheme's would redo what the others compile meanwhile
    os.environ.setdefault("GRANPLATE_COMPILE", "own")
    # the suite's workers share the cores: large verlet runs leave solver.threads at one
    # thread (tests/test_blocks.py sets it where threads are what it checks)
    os.environ.setdefault("GRANPLATE_THREADS", "1")
    _compile_kernel_sets_once()
    yield


def _compile_kernel_sets_once() -> None:
    """Under pytest-xdist, each worker compiles the kernel sets (results.kernels) that no
    worker has compiled yet, one set at a time under a lock the workers share, before its
    first test: the even workers from the first set on, the odd ones from the last, so that
    no set is compiled twice (numba's disk cache serves it to the others) and both cores
    compile. Without xdist, or where a set cannot compile, the tests compile what they use."""
    import hashlib
    import os
    import tempfile

    worker = os.environ.get("PYTEST_XDIST_WORKER", "")
    if not worker or int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1")) < 2:
        return
    try:
        import fcntl
    except ImportError:  # not on this platform: each worker compiles what it uses
        return
    import granplate
    from granplate.results import kernels

    sets = list(kernels.KERNEL_SETS)
    if int(worker.removeprefix("gw") or 0) % 2:
        sets.reverse()
    package = str(Path(granplate.__file__).resolve().parent)
    locks = Path(tempfile.gettempdir()) / f"granplate-compile-{hashlib.sha1(package.encode()).hexdigest()[:12]}"
    locks.mkdir(exist_ok=True)
    for k in sets:
        with open(locks / f"{k.name}.lock", "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            try:
                if kernels.missing((k,)):
                    kernels.compile_set(k)
            except Exception:  # noqa: BLE001 - the tests then compile what they use, and say what fails
                pass


def two_spheres(
    v: float,
    alpha_n: float = 0.0,
    radius: float = 0.01,
    material: str = "steel",
    dt: float = 1e-8,
    t_end: float = 1e-4,
    out: float = 1e-7,
    **contact,
) -> Scenario:
    """Two identical spheres approaching head-on, each at speed v [m/s], just touching."""
    return Scenario(
        name="two-spheres",
        granules=(
            Granule(x=radius, y=0.05, radius=radius, material=material, label="a", vx=v),
            Granule(x=3 * radius, y=0.05, radius=radius, material=material, label="b", vx=-v),
        ),
        load=Load(kind="none"),
        contact=Contact(alpha_n=alpha_n, pairs=(), **contact),
        time=TimeSettings(t_end=t_end, dt_initial=dt, dt_max=dt, output_interval=out, field_interval=out),
    )


def sphere_on_wall(
    vx: float,
    vy: float,
    radius: float = 0.01,
    mu: float = 0.099,
    alpha_n: float = 0.0,
    dt: float = 1e-8,
    t_end: float = 1e-4,
    out: float = 1e-7,
) -> Scenario:
    """A sphere touching the rigid floor y = 0 with velocity (vx, vy) [m/s]."""
    return Scenario(
        name="sphere-on-wall",
        granules=(Granule(x=0.05, y=radius, radius=radius, material="steel", label="s", vx=vx, vy=vy),),
        walls=(Wall(normal=(0.0, -1.0), offset=0.0, label="floor"),),
        load=Load(kind="none"),
        contact=Contact(alpha_n=alpha_n, mu=mu, pairs=()),
        time=TimeSettings(t_end=t_end, dt_initial=dt, dt_max=dt, output_interval=out, field_interval=out),
    )


def script_module(path: Path, name: str):
    """A script of docs/ (not a package module), imported from its file."""
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def section_titles(blocks) -> list[str]:
    """The titles of a report's sections and subsections (its h2 and h3 blocks)."""
    return [b.text for b in blocks if b.kind in ("h2", "h3")]
