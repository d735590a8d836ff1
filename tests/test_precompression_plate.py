"""Precompression against the plane's plate (granplate.model.static with the plate condensed
to its contacts): the truth is statics. A granule pressed onto the plate by a wall carries F,
and the plate's deflection under it is the compliance of an independent static finite-element
solve (scikit-fem's own plane-stress elasticity form, K u = f) times F; the paper's packing,
precompressed, stays at rest without a shock, its plate's contacts carrying the force;
with a shock eq. (11) holds at every step from the stored energy (contacts + plate).
(Gravity with the plate: the static state about its sag, tests/test_gravity_plate.py.)"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

import granplate as gp
from granplate.model.arrays import build_model
from granplate.physics.contact import COEF_A

#: A 2 x 8 plate at x0 = 0.02 m (corner nodes every 12.5 mm), one steel granule on the node
#: at y = 0.05 m, the wall "push" on its other side.
ONE = """
name = "one-on-plate"
[[granules]]
x = 0.015
y = 0.05
radius = 0.005
material = "steel"
[[walls]]
label = "push"
normal = [-1.0, 0.0]
offset = -0.01
[plate]
x0 = 0.02
nx = 2
ny = 8
rigid_layer_width = 0.001
{modes}
[load]
kind = "none"
[precompression]
target = "wall push"
force = 5.0
[time]
t_end = 2e-6
output_interval = 1e-6
"""


def static_compliance(plate, y: float) -> float:
    """The plate's static compliance [m/N] in x at its left-edge node at height y: K u = e_x
    solved with scikit-fem's plane-stress elasticity form on the Q8 mesh, top and bottom
    clamped (the rigid layer narrower than an element: the node alone)."""
    from scipy.sparse.linalg import spsolve
    from skfem import Basis, ElementQuadS2, ElementVector, MeshQuad, asm
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    mesh = MeshQuad.init_tensor(
        np.linspace(plate.x0, plate.x0 + plate.width, plate.nx + 1), np.linspace(0.0, plate.height, plate.ny + 1)
    )
    basis = Basis(mesh, ElementVector(ElementQuadS2()), intorder=4)
    steel = gp.preset("steel-r1").material("steel")
    lam, mu = lame_parameters(steel.E, steel.nu)
    lam = 2.0 * lam * mu / (lam + 2.0 * mu)  # plane stress
    K = asm(linear_elasticity(lam, mu), basis).tocsr() * plate.thickness
    xy = basis.doflocs  # (2, n_dofs): each dof's node
    clamped = np.flatnonzero((np.abs(xy[1]) < 1e-12) | (np.abs(xy[1] - plate.height) < 1e-12))
    free = np.setdiff1d(np.arange(K.shape[0]), clamped)
    vertex = int(np.flatnonzero((np.abs(mesh.p[0] - plate.x0) < 1e-12) & (np.abs(mesh.p[1] - y) < 1e-12))[0])
    dof = int(basis.nodal_dofs[0, vertex])  # its x dof
    f = np.zeros(K.shape[0])
    f[dof] = 1.0
    u = np.zeros(K.shape[0])
    u[free] = spsolve(K[free][:, free].tocsc(), f[free])
    return float(u[dof])


@pytest.mark.parametrize("modes", ['modes = "all"', 'modes = "truncated"\nmax_frequency = 2e5'])
def test_a_granule_pressed_onto_the_plate_deflects_it_by_its_static_compliance(modes):
    """The granule's contacts carry F (wall and plate, at t = 0 in the Dataset too), its overlaps
    are (F / A)^(2/3), and the plate's deflection under it is the independent static solve's
    compliance x F, with every mode and with a truncated basis and its residual compliance."""
    s = gp.loads(ONE.format(modes=modes))
    model = build_model(s)
    force = 5.0
    if "truncated" in modes:
        assert model.plate_arrays.resid.shape == (2, 2) and len(model.plate_arrays.omega2) < 60
    u = model.plate_u0[0]
    assert u == pytest.approx(static_compliance(s.plate, 0.05) * force, rel=1e-6)
    a = model.granular.pc_coef[0, COEF_A]
    x = model.initial_state[0, 0]
    assert s.plate.x0 + u - (x + 0.005) == pytest.approx(-((force / a) ** (2.0 / 3.0)), rel=1e-6)
    ds = gp.simulate(s, progress=False)
    assert float(ds["contact_normal_force"].values[0, 0]) == pytest.approx(force, rel=1e-7)
    assert float(ds["wall_force"].values[0, 0]) == pytest.approx(force, rel=1e-7)
    # the plate's stored energy is its strain energy 1/2 F u, part of E_initial
    assert float(ds["E_plate"].values[0]) == pytest.approx(0.5 * force * u, rel=1e-6)
    assert np.max(np.abs(ds["x"].values - ds["x"].values[0])) < 1e-12


def paper_packing(force: float, q0: float, t_end: float, extra: dict | None = None):
    """The paper's packing (preset ptfe-r05) pressed by its left wall onto the plate."""
    changes = {
        "precompression.target": "wall left",
        "precompression.force": force,
        "load.q0": q0,
        "time.t_end": t_end,
        **(extra or {}),
    }
    return gp.with_changes(gp.preset("ptfe-r05"), changes)


def test_the_precompressed_paper_packing_stays_at_rest_on_its_plate():
    """No shock: nothing moves (1e-12 m), the plate's energy stays its static strain energy,
    the plate's contacts carry the precompression between them (the top and bottom walls
    take only the vertical components) and every contact force balances at t = 0."""
    s = paper_packing(100.0, 0.0, 2e-5)
    ds = gp.simulate(s, progress=False)
    fn = ds["contact_normal_force"].values
    assert float(fn[0].sum()) == pytest.approx(100.0, rel=1e-7)
    np.testing.assert_allclose(fn, np.broadcast_to(fn[0], fn.shape), rtol=1e-8)
    assert float(ds["wall_force"].sel(wall="left").values[0]) == pytest.approx(100.0, rel=1e-8)
    assert np.max(np.abs(ds["x"].values - ds["x"].values[0])) < 1e-12
    assert np.max(np.abs(ds["y"].values - ds["y"].values[0])) < 1e-12
    ep = ds["E_plate"].values
    assert ep[0] > 0.0
    np.testing.assert_allclose(ep, np.full_like(ep, ep[0]), rtol=1e-9)
    assert np.max(np.abs(ds["energy_residual"].values)) < 1e-9


def test_a_shock_on_the_precompressed_packing_balances_its_energy():
    """With the paper's moderate shock, eq. (11) holds at every step from E_initial, the
    contacts' and the plate's stored energy at t = 0 (the plate's 1/2 F . u of the static
    state); the plate's energy about its static state (E_plate_dynamic) starts at 0 and stays
    within the shock's energy (the static state is stationary: E_shock - D is the sum of
    non-negative energies about it), and its peak over E_shock is the summary's share."""
    from granplate.results.dataset import summary

    s = paper_packing(200.0, 1e4, 1.5e-4)
    model = build_model(s)
    ds = gp.simulate(s, progress=False)
    e_static_plate = 0.5 * float(np.asarray(ds["contact_normal_force"].values[0]) @ model.plate_u0[0::2])
    ep = ds["E_plate"].values
    assert float(ep[0]) == pytest.approx(e_static_plate, rel=1e-6)
    assert ds.attrs["E_initial"] == pytest.approx(float(ds["E_granular"].values[0] + ep[0]), rel=1e-12)
    assert np.max(np.abs(ds["energy_residual_max"].values)) < s.solver.energy_tol
    e_shock = ds["E_shock"].values
    # the residual against E_shock alone (eq. 11's scale holds the stored energy too)
    lhs = ds["E_granular"].values + ep + ds["D_viscous"].values + ds["D_friction"].values
    assert np.max(np.abs(lhs - ds.attrs["E_initial"] - e_shock)) < 1e-4 * e_shock[-1]
    dyn = ds["E_plate_dynamic"].values
    assert abs(dyn[0]) < 1e-12 * ep[0]
    assert np.all(dyn >= -1e-6 * e_shock[-1]) and np.all(dyn <= e_shock + 1e-6 * e_shock[-1])
    assert np.max(ep - ep[0]) > 1.2 * np.max(dyn)  # E_p - E_p(0) holds the static forces' work too
    share = summary(ds)["ep_dynamic_max_fraction"]
    assert share == pytest.approx(float(np.max(dyn)) / e_shock[-1], rel=1e-9)
    assert share > 1e-3


def test_a_granule_between_the_faces_nodes_is_refused_by_name():
    """A granule touching the plate's face between nodes at t = 0 (a patch contact) cannot be
    precompressed: refused before anything runs, naming precompression.target and the granule."""
    from granplate.errors import ScenarioError
    from granplate.setup.validate import validate

    s = gp.loads(ONE.format(modes="").replace("y = 0.05\n", "y = 0.055\n", 1))
    with pytest.raises(ScenarioError, match="between nodes") as e:
        validate(s)
    assert e.value.field == "precompression.target"


def test_a_3d_plate_is_valid():
    """A 3D [plate] (an elastic solid) is part of the static state (model.body_static;
    tests/test_body_gravity.py): a precompression of docs/examples/3d-fcc-on-plate.toml (its
    layout's wall xmin) passes validation."""
    from granplate.setup.validate import validate

    text = (Path(__file__).resolve().parents[1] / "docs" / "examples" / "3d-fcc-on-plate.toml").read_text()
    text = text.replace("walls = []", 'walls = ["xmin"]') + '\n[precompression]\ntarget = "wall xmin"\nforce = 1.0\n'
    validate(gp.loads(text))


STUDY = Path(__file__).resolve().parents[1] / "docs" / "studies" / "precompressed-protector.toml"


def test_the_precompressed_protector_study_runs_on_a_small_grid(tmp_path):
    """docs/studies/precompressed-protector.toml, cut to a 2 x 2 grid (the extreme forces and
    shocks) over 40 us, runs through `sweep`: every design completes with eq. (11) held, and
    the plate's share of the shock is a fraction in [0, 1]."""
    import tomllib

    from distributed import Client

    from granplate.study.spec import parse_study
    from granplate.study.sweep import sweep

    doc = tomllib.loads(STUDY.read_text())
    assert len(parse_study(doc, STUDY.parent).designs) == 15
    doc["parameters"] = {"precompression.force": [10.0, 1000.0], "load.q0": [2e3, 5e4]}
    doc["set"] = {"time.t_end": 4e-5}
    study = parse_study(doc, STUDY.parent)
    with Client(processes=False, n_workers=1, threads_per_worker=1, dashboard_address=None) as client:
        sweep(study, tmp_path, client=client, progress=False)
    with open(tmp_path / "results.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 4
    for row in rows:
        assert row["status"] == "ok" and abs(float(row["energy_residual_max"])) < 1e-4
        assert 0.0 <= float(row["ep_dynamic_max_fraction"]) <= 1.0


def test_the_committed_study_table_is_of_its_study_file_and_on_the_page():
    """docs/studies/precompressed-protector/results.csv holds the study file's 15 designs, all
    completed with eq. (11) held and a share in [0, 1], and the table of
    docs/how-to/precompressed-protector.md is that table's ep_dynamic_max_fraction. Nothing is
    run: the table is read."""
    from granplate.study.spec import load_study

    study = load_study(STUDY)
    with open(STUDY.parent / "precompressed-protector" / "results.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == len(study.designs) == 15
    for row, design in zip(rows, study.designs):
        assert tuple(float(row[n]) for n in study.names) == pytest.approx(design, rel=1e-12)
        assert row["status"] == "ok" and abs(float(row["energy_residual_max"])) < 1e-4
        assert 0.0 <= float(row["ep_dynamic_max_fraction"]) <= 1.0
    assert (STUDY.parent / "precompressed-protector" / "study.toml").read_text() == STUDY.read_text()
    page = (STUDY.parents[1] / "how-to" / "precompressed-protector.md").read_text()
    block = page.split("<!-- precompressed-protector: begin -->\n")[1].split("\n<!-- precompressed-protector: end -->")[
        0
    ]
    cells = {}
    for line in block.splitlines()[3:]:
        first, *shares = [c.strip() for c in line.strip("|").split("|")]
        cells[float(first)] = shares
    for row in rows:
        column = [2e3, 1e4, 5e4].index(float(row["load.q0"]))
        shown = cells[float(f"{float(row['precompression.force']):.3g}")][column]
        assert shown == f"{100 * float(row['ep_dynamic_max_fraction']):.2f}%"
