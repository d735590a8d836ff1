"""The compiled loop's parts as units: the plate compliance G(h) of criterion (8), the
dense solve of the Newton step, each scheme's single step, and the scheme registry."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg

from granplate.model.inputs import SCHEME_NAMES, Config, Granular, PlateArrays, no_body, scheme_number
from granplate.physics.contact import N_COEF
from granplate.solver import loop, schemes, state as S
from granplate.solver.plate_modal import step_matrices
from granplate.dense import solve_dense


def test_compliance_is_the_driving_block_of_the_newmark_matrix():
    """G(h) = Phi_d diag(1/(1 + h^2 w^2/4)) Phi_d^T equals the driving-DOF block of
    (M + h^2 K / 4)^-1 of a random plate with all its modes (dense solve)."""
    rng = np.random.default_rng(3)
    n = 7
    a = rng.normal(size=(n, n))
    b = rng.normal(size=(n, n))
    mass = a @ a.T + n * np.eye(n)
    stiff = 1e6 * (b @ b.T + np.eye(n))
    w2, phi = scipy.linalg.eigh(stiff, mass)  # mass-normalised: phi^T M phi = 1
    drive = [1, 4, 5, 6]
    p = PlateArrays(omega2=w2, phi_d=np.ascontiguousarray(phi[drive]), load_modal=np.zeros(n))
    h = 2e-3
    dmode, gmat = np.zeros(n), np.zeros((4, 4))
    step_matrices(h, p, dmode, gmat)
    dense = np.linalg.inv(mass + 0.25 * h * h * stiff)[np.ix_(drive, drive)]
    np.testing.assert_allclose(gmat, dense, rtol=1e-10, atol=1e-14 * np.abs(dense).max())


def test_dense_solve_matches_numpy():
    """solve_dense (Gaussian elimination, partial pivoting) = numpy.linalg.solve."""
    rng = np.random.default_rng(5)
    for n in (1, 2, 6):
        m = rng.normal(size=(n, n))
        if n > 1:
            m[0, 0] = 0.0  # needs a pivot swap
        rhs = rng.normal(size=n)
        want = np.linalg.solve(m, rhs)
        x = rhs.copy()
        assert solve_dense(m.copy(), x) > 0.0
        np.testing.assert_allclose(x, want, rtol=1e-10)
    singular = np.array([[1.0, 2.0], [2.0, 4.0]])  # rank 1: its second pivot vanishes
    assert solve_dense(singular, np.array([1.0, 2.0])) == 0.0


def one_mode_run(scheme: str, omega_h: float, n_steps: int = 1, budget: int = 100):
    """A plate of one mode (omega = 2 pi 1 kHz, q(0) = 1), no granules, stepped to
    n_steps h by calls to advance with `budget` attempts each."""
    w = 2 * math.pi * 1000.0
    h = omega_h / w
    ei, ef = np.zeros(0, np.int64), np.zeros(0)
    g = Granular(
        mass=ef,
        inertia=ef,
        radius=ef,
        pair_ij=np.zeros((0, 2), np.int64),
        pair_coef=np.zeros((0, N_COEF)),
        wall_i=ei,
        wall_geo=np.zeros((0, 3)),
        wall_coef=np.zeros((0, N_COEF)),
        wall_w=ei,
        pc_i=ei,
        pc_x=ef,
        pc_coef=np.zeros((0, N_COEF)),
        shock_force=ef,
        shock_torque=ef,
    )
    p = PlateArrays(omega2=np.array([w * w]), phi_d=np.zeros((0, 1)), load_modal=np.zeros(1))
    cfg = Config(
        q0=0.0,
        duration=1.0,
        clip=True,
        lambda_target=0.5,
        rtol=1e-9,
        atol=1e-10,
        max_iter=10,
        energy_tol=1.0,
        dt_max=h,
        dt_min=h * 1e-3,
        out_dt=n_steps * h,
        t_end=n_steps * h,
        load_on_plate=False,
        arm_shrink=0.0,
        scheme=scheme_number(scheme),
        error_tol=1e-3,
        force_floor=0.0,
    )
    st, w_, out = S.new_state(0, 1, 0), S.new_work(0, 1, 0), S.new_output(np.array([0.0, n_steps * h]), 0, 1, 0)
    sw = schemes.scheme(scheme).new_scratch(0, 1, 0)
    b = no_body(0, 1)
    st.q[0] = 1.0
    loop.initialise(st, g, p, cfg, w_)
    loop.record(0, st, g, p, w_, out)
    st.count[S.C_OUT] = 1
    calls = 0
    status = S.PAUSED
    while status == S.PAUSED:
        status = loop.advance(n_steps * h, budget, g, p, b, cfg, st, w_, sw, out)
        calls += 1
    return status, st, out, calls


@pytest.mark.parametrize("omega_h", [0.3, 0.9])
def test_paper_step_is_newmark_average_acceleration(omega_h):
    """One paper-scheme step of a free mode: q1 = (1 - x^2/4)/(1 + x^2/4), x = omega h
    (Newmark, beta 1/4, gamma 1/2, from q0 = 1 at rest), recorded at the output time."""
    status, st, out, _ = one_mode_run("paper", omega_h)
    x2 = omega_h**2
    assert status == S.OK and st.count[S.C_STEPS] == 1 and st.count[S.C_OUT] == 2
    assert st.q[0] == pytest.approx((1 - x2 / 4) / (1 + x2 / 4), rel=1e-13)
    assert out.q[1, 0] == st.q[0]


@pytest.mark.parametrize("omega_h", [0.3, 0.9])
def test_implicit_step_is_exact_for_a_free_mode(omega_h):
    """One implicit-scheme step of a free mode with omega h <= 1: q1 = cos(omega h),
    q1' = -omega sin(omega h) (exact modal integration)."""
    status, st, out, _ = one_mode_run("implicit", omega_h)
    w = 2 * math.pi * 1000.0
    assert status == S.OK and st.count[S.C_STEPS] == 1
    assert st.q[0] == pytest.approx(math.cos(omega_h), rel=1e-13)
    assert st.qd[0] == pytest.approx(-w * math.sin(omega_h), rel=1e-12)


@pytest.mark.parametrize("scheme", SCHEME_NAMES)
def test_step_budget_pauses_and_resumes_identically(scheme):
    """advance with a budget of one attempt per call pauses (PAUSED) after each step and,
    called again, ends where one unbounded call ends, bit for bit."""
    status_a, st_a, _, calls_a = one_mode_run(scheme, 0.5, n_steps=8)
    status_b, st_b, _, calls_b = one_mode_run(scheme, 0.5, n_steps=8, budget=1)
    assert status_a == status_b == S.OK and calls_a == 1 and calls_b >= 8
    assert st_a.count[S.C_STEPS] == st_b.count[S.C_STEPS]
    assert (st_a.q[0], st_a.qd[0]) == (st_b.q[0], st_b.qd[0])


def test_registry_names_and_refusals():
    """Every name of SCHEME_NAMES has a module with the interface; unknown ones are refused."""
    assert tuple(schemes.SCHEMES) == SCHEME_NAMES
    for i, name in enumerate(SCHEME_NAMES):
        mod = schemes.scheme(name)
        assert schemes.scheme(i) is mod and mod.NAME == name
        for hook in (
            "plan",
            "prepare_level",
            "attempt",
            "judge",
            "commit",
            "next_level",
            "contact_placed",
            "contacts_moved",
            "new_scratch",
        ):
            assert callable(getattr(mod, hook))
    with pytest.raises(ValueError, match="allowed paper, implicit"):
        schemes.scheme("leapfrog")
    with pytest.raises(ValueError, match="scheme number 7"):
        schemes.scheme(7)
    with pytest.raises(NotImplementedError):
        schemes.attempt(None, 0, 0, 0, None, None, None, None, None, None)
