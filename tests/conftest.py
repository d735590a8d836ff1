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
    yield


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
