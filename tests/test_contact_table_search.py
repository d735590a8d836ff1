"""The contact table's pairs from one compiled cell-grid pass (model.neighbours.reaching_pairs)
per block of output times against the k-d tree search of every touching pair at each
output time that made them before:
the same table bit for bit, in the plane and in space, with walls and a yielding law; and
the grid's pairs against all pairs compared by the same test."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from granplate.bench.scaling_space import launched_fcc
from granplate.errors import YieldWarning
from granplate.model.arrays import build_model
from granplate.model.neighbours import reaching_pairs
from granplate.results import contact_table as ct
from granplate.setup.io import loads
from granplate.setup.pairs import all_pairs
from granplate.setup.run_checks import contact_steps
from granplate.solver.driver import run

pytestmark = pytest.mark.filterwarnings("ignore", category=YieldWarning)


def discs_in_a_box() -> str:
    """A 2D scenario: 30 discs on a hexagonal net, touching along its rows, with random
    speeds, between three walls (the bottom row on the floor)."""
    rng = np.random.default_rng(7)
    lines = ['name = "discs-in-a-box"', "dimension = 2"]
    for k in range(30):
        row, col = divmod(k, 6)
        x = 0.0021 + 0.002 * col + (0.001 if row % 2 else 0.0)
        y = 0.001 + 0.0017321 * row
        vx, vy = (float(v) for v in rng.uniform(-0.5, 0.5, 2))
        lines += ["[[granules]]", f"x = {x!r}", f"y = {y!r}", f"vx = {vx!r}", f"vy = {vy!r}", "radius = 0.001"]
        lines.append('material = "steel"')
    for label, normal, offset in (
        ("left", "[-1.0, 0.0]", 0.0),
        ("right", "[1.0, 0.0]", 0.0155),
        ("floor", "[0.0, -1.0]", 0.0),
    ):
        lines += ["[[walls]]", f'label = "{label}"', f"normal = {normal}", f"offset = {offset!r}"]
    lines += ['[load]\nkind = "none"', "[contact]\nmu = 0.3"]
    lines += ["[time]\nt_end = 4e-6\noutput_interval = 2e-7\nfield_interval = 2e-7", '[solver]\nscheme = "verlet"']
    return "\n".join(lines)


def spheres_launched():
    """A 3D FCC packing of 108 touching spheres, its first plane launched, Thornton's law
    (the table needs the overlaps between its times), the table every other output time."""
    s = launched_fcc((3, 3, 3), mu=0.2, t_end=3e-6, scheme="verlet", outputs=30)
    s = dataclasses.replace(s, contact=dataclasses.replace(s.contact, normal_law="thornton"))
    return dataclasses.replace(s, time=dataclasses.replace(s.time, contact_interval=2e-7))


@pytest.mark.parametrize("make", [discs_in_a_box, spheres_launched], ids=["plane", "space"])
def test_the_grids_table_is_the_k_d_trees_bit_for_bit(make, monkeypatch):
    """Every variable of the table equals, bit for bit, the one whose pairs the k-d tree
    search of all touching pairs gave at each time (results.contact_table.touching_pairs)."""
    s = make()
    s = loads(s) if isinstance(s, str) else s
    model = build_model(s)
    rec = run(model)
    args = (model, rec.out, rec.n_valid, rec.contacts.peaks, contact_steps(model.scenario.time))
    new, new_coords = ct.contact_table(*args)
    monkeypatch.setattr(ct, "block_candidates", lambda ys, r: None)  # one output time per block
    monkeypatch.setattr(ct, "reaching", ct.touching_pairs)
    old, old_coords = ct.contact_table(*args)
    assert len(new["link_time"]) > 100 and set(new) == set(old)
    assert (new["link_partner"].values < 0).any() == (len(model.walls) > 0)
    for name in old:
        np.testing.assert_array_equal(new[name].values, old[name].values, err_msg=name)
    np.testing.assert_array_equal(new_coords["link_table_time"][1], old_coords["link_table_time"][1])


@pytest.mark.parametrize("dimension", [2, 3])
def test_the_grids_pairs_are_all_pairs_within_reach(dimension):
    """reaching_pairs equals all pairs compared (setup.pairs.all_pairs's order), their squared
    distance at most ((R_i + R_j) reach)^2, for mixed radii, on its grid and on the k-d tree
    it takes for a sparse assembly."""
    rng = np.random.default_rng(3)
    r = rng.uniform(0.5e-3, 1.5e-3, 60)
    for spread in (0.01, 10.0):  # dense: the grid; sparse (one far granule): the k-d tree
        p = rng.uniform(0.0, 0.01, (60, dimension))
        p[0] *= spread / 0.01
        cand = all_pairs(p, 2 * r.max() * 1.01)
        d2 = np.sum((p[cand[:, 1]] - p[cand[:, 0]]) ** 2, axis=1)
        want = cand[d2 <= ((r[cand[:, 0]] + r[cand[:, 1]]) * 1.001) ** 2]
        got = reaching_pairs(p, r, 1.001)
        assert len(want) > 20
        np.testing.assert_array_equal(got, want)
