"""The truncated plate basis with static correction (docs/model.md section 4.5) against
the full one, and the plate's size checks (granplate.setup.plate_cost)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from granplate import plate as gp
from granplate.bench.plates import format_plate_table, parse_meshes
from granplate.errors import ScenarioError
from granplate.plate.constraints import reduce_matrix
from granplate.plate.face import face_forces, face_rows
from granplate.setup import plate_cost
from granplate.setup.presets import preset
from granplate.setup.scenario import Plate
from granplate.setup.validate import validate

X0 = 0.01 + 2 * math.sqrt(0.02**2 - 0.01**2) + 0.01  # the paper's plate position, R2 = R1
CONTACTS = (0.09, 0.07, 0.05, 0.03, 0.01)
#: a cut-off that keeps 8 of the 4 x 40 plate's 1,082 modes: a hard truncation
CUT_HZ = 6.0e4


@pytest.fixture(autouse=True)
def _private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("GRANPLATE_CACHE", str(tmp_path / "cache"))


@pytest.fixture(scope="module")
def full() -> gp.PlateModel:
    return gp.build_plate(Plate(), X0, CONTACTS, cache=False)


@pytest.fixture(scope="module")
def truncated() -> gp.PlateModel:
    return gp.build_plate(Plate(modes="truncated", max_frequency=CUT_HZ), X0, CONTACTS, cache=False)


def test_auto_keeps_the_paper_mesh_dense(full):
    """ "auto" gives the paper's 4 x 40 mesh every mode, without a static part."""
    assert full.n_modes == full.n_red and not full.truncated and full.resid.shape == (0, 0)
    assert plate_cost.basis_kind("auto", full.n_red) == "all"
    assert plate_cost.basis_kind("auto", plate_cost.DENSE_DOF_LIMIT + 1) == "truncated"
    # a plate the static correction does not cover keeps every mode
    assert not plate_cost.truncation_supported((), False) and not plate_cost.truncation_supported(("top",), True)
    assert plate_cost.basis_kind("auto", plate_cost.DENSE_DOF_LIMIT + 1, supported=False) == "all"


def test_truncated_modes_are_the_lowest_full_modes(full, truncated):
    """The sparse eigensolver finds the full basis' modes below the cut-off, signed alike."""
    nm = truncated.n_modes
    assert 1 <= nm < 20 and truncated.omega[-1] <= 2 * math.pi * CUT_HZ < full.omega[nm]
    np.testing.assert_allclose(truncated.omega, full.omega[:nm], rtol=1e-10)
    np.testing.assert_allclose(truncated.Phi, full.Phi[:, :nm], atol=1e-8 * np.abs(full.Phi).max())


def test_static_compliance_at_the_contacts_is_exact(full, truncated):
    """Phi_d diag(1/omega^2) Phi_d^T + R equals K_r^-1 restricted to the driving dofs, and
    with a truncated basis R is a share of it that the modes miss (positive semi-definite,
    a few per cent here)."""
    K_r = gp.reduce_matrix(full.stiffness_matrix(), full.T).tocsc()
    drive = full.drive_dofs.ravel()
    unit = np.zeros((full.n_red, drive.size))
    unit[drive, np.arange(drive.size)] = 1.0
    exact = spla.splu(K_r).solve(unit)[drive]
    scale = np.abs(exact).max()
    np.testing.assert_allclose(truncated.static_compliance(), exact, rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(full.static_compliance(), exact, rtol=0, atol=1e-9 * scale)
    assert np.linalg.eigvalsh(truncated.resid).min() > -1e-12 * scale
    assert np.abs(truncated.resid).max() > 0.01 * scale


def test_criterion_8_compliance_tends_to_the_full_one(full, truncated):
    """G(h) with the static part 4 R / h^2 approaches the full G(h) once h omega >> 1 for
    every dropped mode (relative error ~ (omega_cut / omega_dropped)^2 ... tiny at h = 1 ms)."""
    for h in (1e-3, 1e-4):
        g_f, g_t = full.compliance(h), truncated.compliance(h)
        np.testing.assert_allclose(g_t, g_f, rtol=0, atol=2e-3 * np.abs(g_f).max())


def test_static_displacement_field_is_exact(full, truncated):
    """Under static contact forces the whole displacement field and the stresses
    T (Phi q + Psi F) agree with the full basis (every mode static)."""
    rng = np.random.default_rng(3)
    F = rng.normal(size=(2, full.drive_dofs.size))
    q_full = (F @ full.phi_drive) / full.omega**2
    q_trunc = (F @ truncated.phi_drive) / truncated.omega**2
    u_f = full.full_dofs(q_full)
    u_t = truncated.full_dofs(q_trunc, F)
    np.testing.assert_allclose(u_t, u_f, rtol=0, atol=1e-8 * np.abs(u_f).max())
    vm_f, vm_t = full.von_mises(q_full), truncated.von_mises(q_trunc, F)
    np.testing.assert_allclose(vm_t, vm_f, rtol=0, atol=1e-7 * vm_f.max())
    e_f = full.energy(q_full, 0 * q_full)
    e_t = truncated.energy(q_trunc, 0 * q_trunc, F)
    np.testing.assert_allclose(e_t, e_f, rtol=1e-8)
    np.testing.assert_allclose(e_f, 0.5 * np.einsum("ki,ij,kj->k", F, full.static_compliance(), F), rtol=1e-8)


def _steel(t_end: float, **plate) -> object:
    s = preset("steel-r1")
    return dataclasses.replace(
        s, plate=dataclasses.replace(s.plate, **plate), time=dataclasses.replace(s.time, t_end=t_end)
    )


def test_short_run_agrees_with_the_full_basis():
    """steel-r1 to 0.5 ms (the shock has reached the plate): the truncated basis with a
    cut-off of 3e5 Hz (134 of 1,082 modes) reproduces the full run's summary within 0.5%,
    its energy residual within solver.energy_tol."""
    from granplate import simulate, summary

    f = summary(simulate(_steel(5e-4), progress=False))
    ds = simulate(_steel(5e-4, modes="truncated", max_frequency=3e5), progress=False)
    t = summary(ds)
    assert t["energy_residual_max"] <= preset("steel-r1").solver.energy_tol
    for key in (
        "ep_max_fraction",
        "ep_final_fraction",
        "eg_max_fraction",
        "dissipated_fraction",
        "max_von_mises",
        "max_eps_yy",
        "e_shock",
    ):
        assert t[key] == pytest.approx(f[key], rel=5e-3), key
    assert f["ep_max_fraction"] > 0.05  # the plate took part


def test_truncated_plate_is_refused_where_unsupported():
    """The paper scheme and a load on the plate's edge are refused, naming the field and why."""
    s = preset("steel-r1")
    bad = dataclasses.replace(
        s, plate=dataclasses.replace(s.plate, modes="truncated"), solver=dataclasses.replace(s.solver, scheme="paper")
    )
    with pytest.raises(ScenarioError, match="solver.scheme") as refused:
        validate(bad)
    # the refusal says why (the massless static part defeats criterion (8)) and what to use
    assert "R_tt / h" in str(refused.value) and "'implicit'" in str(refused.value)
    assert "plate.modes = 'all'" in str(refused.value)
    b = preset("bare-plate")
    with pytest.raises(ScenarioError, match="load.target"):
        validate(dataclasses.replace(b, plate=dataclasses.replace(b.plate, modes="truncated")))
    with pytest.raises(ScenarioError, match="plate.modes"):
        validate(dataclasses.replace(s, plate=dataclasses.replace(s.plate, modes="some")))
    with pytest.raises(ScenarioError, match="plate.max_frequency"):
        validate(dataclasses.replace(s, plate=dataclasses.replace(s.plate, max_frequency=-1.0)))


def test_plate_too_large_is_refused_with_the_estimate():
    """A dense basis beyond the memory is refused before anything is built, saying how
    much it needs and what to change; "auto" takes the truncated basis instead."""
    with pytest.raises(ScenarioError, match=r"plate.modes.*GB.*truncated"):
        plate_cost.check_fits("all", 16_000, "all", memory=2e9)
    plate_cost.check_fits("truncated", 16_000, "auto", memory=2e9)
    s = preset("steel-r1")
    huge = dataclasses.replace(s, plate=dataclasses.replace(s.plate, nx=64, ny=640, modes="all"))
    with pytest.raises(ScenarioError, match="plate.modes"):
        validate(huge)  # ~250,000 dofs: ~4 TB dense
    need, seconds = plate_cost.build_estimate("all", 4194)
    assert 0.5e9 < need < 2e9 and 20 < seconds < 120  # the measured 8 x 80: 1.0 GB, 59 s


def test_bench_plate_table_helpers():
    assert parse_meshes("4x40, 8X80") == [(4, 40), (8, 80)]
    with pytest.raises(ValueError, match="--meshes"):
        parse_meshes("4x")
    table = format_plate_table(
        [
            {
                "mesh": "4 x 40",
                "modes": "auto",
                "setup_s": 2.5,
                "rss_setup_mib": 180.0,
                "n_red": 1082,
                "n_modes": 1082,
                "truncated": False,
                "run_s": 16.0,
                "rss_peak_mib": 220.0,
                "summary": {"max_von_mises": 43.6e6, "max_von_mises_disc": 30.3e6},
            },
            {"mesh": "64 x 640", "modes": "all", "refused": "scenario field 'plate.modes'"},
        ]
    )
    assert "| 4 x 40 | all | 1,082 | 1082 | 2.5 | 180 | 16.0 | 220 | 43.6 | 30.3 |" in table
    assert "plate.modes" in table.splitlines()[-1]


def test_bench_plates_command(tmp_path, capsys):
    """`granplate bench --plates` measures a mesh in a fresh process and reports its table."""
    import json

    from granplate.cli import main

    out = tmp_path / "plates.json"
    rc = main(["bench", "--plates", "--meshes", "2x20", "--modes", "truncated", "--t-end", "1e-5", "--json", str(out)])
    assert rc == 0
    (row,) = json.loads(out.read_text())
    assert row["truncated"] and 0 < row["n_modes"] < row["n_red"] == 290
    assert row["setup_s"] > 0 and row["run_s"] > 0 and row["rss_peak_mib"] >= row["rss_setup_mib"] > 0
    assert "| 2 x 20 | truncated | 290 |" in capsys.readouterr().out


def test_plate_basis_fields_round_trip_through_toml():
    """plate.modes and plate.max_frequency are written and read back by the scenario I/O."""
    from granplate.setup import io as scenario_io

    s = preset("steel-r1")
    s = dataclasses.replace(s, plate=dataclasses.replace(s.plate, nx=8, ny=80, modes="truncated", max_frequency=5e5))
    text = scenario_io.dumps(s)
    assert 'modes = "truncated"' in text and "max_frequency = 500000.0" in text
    assert scenario_io.loads(text) == s
    validate(s)


def _exact_face_compliance(model: gp.PlateModel) -> np.ndarray:
    """E K_r^-1 E^T over the face's dofs [m/N] by a direct sparse solve (E = face_rows)."""
    E = face_rows(model.T, model.face_nodes)
    K_r = reduce_matrix(model.stiffness_matrix(), model.T)
    return E @ spla.splu(sp.csc_matrix(K_r)).solve(E.T.toarray())


def test_face_residual_compliance_completes_the_static_response(full, truncated):
    """Over every face dof, phi_face diag(1/omega^2) phi_face^T + R_face is K_r^-1
    restricted to the face (a direct solve) and the full basis' static compliance; R_face
    holds the rigid layers' R at their nodes and is positive semi-definite."""
    exact = _exact_face_compliance(truncated)
    scale = np.abs(exact).max()
    ours = (truncated.phi_face / truncated.omega**2) @ truncated.phi_face.T + truncated.resid_face
    np.testing.assert_allclose(ours, exact, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(ours, (full.phi_face / full.omega**2) @ full.phi_face.T, rtol=0, atol=1e-9 * scale)
    at = [int(np.flatnonzero(np.isclose(truncated.face_y, y))[0]) for y in CONTACTS]
    dofs = np.ravel([[2 * n, 2 * n + 1] for n in at])
    np.testing.assert_allclose(truncated.resid_face[np.ix_(dofs, dofs)], truncated.resid, rtol=0, atol=1e-12 * scale)
    assert np.linalg.eigvalsh(truncated.resid_face).min() > -1e-12 * scale
    assert full.resid_face.shape == (0, 0)


def test_patch_force_static_displacement_is_exact(full, truncated):
    """A static force on a patch between nodes (beyond the rigid layers' contacts): the
    truncated basis' modes plus its static part (full_dofs with the patch force) give the
    full basis' static displacement everywhere."""
    y_p = 0.0604375
    t_model = dataclasses.replace(truncated, contact_y=np.append(truncated.contact_y, y_p))
    f_model = dataclasses.replace(full, contact_y=np.append(full.contact_y, y_p))
    F = np.zeros(2 * len(CONTACTS) + 2)
    F[-2:] = (-3.0, 1.0)  # [N] x, y on the patch
    F[0] = -2.0  # and a rigid layer's
    f_face = face_forces(full.face_y, [y_p], full.patch_width, F[-2:])
    f_red = face_rows(full.T, full.face_nodes).T @ f_face + np.eye(full.n_red)[:, full.drive_dofs.ravel()] @ F[:-2]
    q_full = (full.Phi.T @ f_red) / full.omega**2
    q_trunc = (truncated.Phi.T @ f_red) / truncated.omega**2
    u_f, u_t = f_model.full_dofs(q_full), t_model.full_dofs(q_trunc, F)
    np.testing.assert_allclose(u_t, u_f, rtol=0, atol=1e-8 * np.abs(u_f).max())
    assert np.abs(truncated.full_dofs(q_trunc) - u_f).max() > 0.01 * np.abs(u_f).max()  # the static part matters


def test_face_compliance_enters_the_memory_estimate():
    """The truncated basis' estimate holds the (2 n_face)^2 doubles of R_face: 3.3 MB for
    the 321 face nodes of a 32 x 320 plate."""
    base, _ = plate_cost.build_estimate("truncated", 100_000)
    with_face, _ = plate_cost.build_estimate("truncated", 100_000, n_face=321)
    assert with_face - base == pytest.approx(642**2 * 8.0)
    assert plate_cost.build_estimate("all", 4194, n_face=161) == plate_cost.build_estimate("all", 4194)
