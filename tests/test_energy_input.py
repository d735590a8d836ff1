"""The energy put in, with a load and initial velocities combined: truth is the energy
balance of eq. (11), E_p + E_g + D = E_initial + E_shock(t), and the sign of the load's
power F . v (negative while the loaded disc moves toward the load)."""

from __future__ import annotations

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")

#: Two steel discs moving toward the load (-x) while it pushes the first along +x: the load
#: first takes energy out (its force against the disc's velocity), then, once the disc
#: turns round, puts energy in (the second disc, 2 cm away, keeps E_initial apart from it).
SCENARIO = """
name = "load-against-motion"
[[granules]]
x = 0.01
y = 0.0
radius = 0.005
material = "steel"
label = "a"
vx = -2.0
[[granules]]
x = 0.03
y = 0.0
radius = 0.005
material = "steel"
label = "b"
vx = -1.0
[load]
q0 = 30000.0
duration = 1e-4
length = 0.01
y0 = 0.0
granules = ["a"]
[time]
t_end = 2e-4
"""


@pytest.fixture(scope="module")
def ds():
    import granplate as gp
    from granplate.setup.io import loads

    return gp.simulate(loads(SCENARIO), progress=False)


def test_load_work_splits_into_put_in_and_taken_back():
    """Truth: by hand, the sums of the rises and of the falls of E_shock."""
    from granplate.results.analysis import load_work

    put_in, taken = load_work(np.array([0.0, 1.0, 3.0, 2.0, 2.5, 2.5]))
    assert put_in.tolist() == [0.0, 1.0, 3.0, 3.0, 3.5, 3.5]
    assert taken.tolist() == [0.0, 0.0, 0.0, 1.0, 1.0, 1.0]


def test_the_run_has_both_a_load_taking_energy_back_and_putting_some_in(ds):
    """Truth: F . v < 0 while disc a moves toward the load, > 0 once it has turned round."""
    e = ds.E_shock.values
    assert e.min() < -1e-6 and e[-1] > e.min() + 1e-6
    assert ds.attrs["E_initial"] > 0


def test_summary_shows_no_negative_energy_and_no_share_above_one(ds):
    """Truth: eq. (11) at every output, E_p + E_g + D = E_initial + E_shock(t) <= E_initial
    + the load's work put in so far = e_in, so every share is at most 1 (up to the residual)."""
    import granplate as gp
    from granplate.cli import SHARES, format_summary

    s = gp.summary(ds)
    assert s["e_shock"] > 0 and s["e_load_taken"] > 0 and s["e_initial"] > 0
    assert s["e_in"] == pytest.approx(s["e_shock"] + s["e_initial"], rel=1e-12)
    assert s["e_shock"] - s["e_load_taken"] == pytest.approx(float(ds.E_shock[-1]), rel=1e-9, abs=1e-15)
    for key in SHARES:
        assert s[key] is None or s[key] <= 1.0 + s["energy_residual_max"], key
    text = format_summary(s)
    assert "E_shock, work the load put in" in text and "of it taken back by the load" in text
    energies = [float(line.split()[-2]) for line in text.splitlines() if line.endswith(" J")]
    assert len(energies) == 4 and min(energies) > 0  # E_shock, taken back, E_initial, E_in
    assert "granules moving toward it" in text  # the note says why


def test_a_share_above_one_gets_a_note():
    """Truth: the summary table says why when a share exceeds 1 (here by round-off)."""
    from granplate.cli import summary_notes

    notes = summary_notes(
        {"e_in": 1.0, "e_shock": 1.0, "e_load_taken": 0.0, "eg_max_fraction": 1.0 + 1e-8, "energy_residual_max": 2e-8}
    )
    assert len(notes) == 1 and "eg_max_fraction above 1" in notes[0] and "within the energy residual" in notes[0]
    assert summary_notes({"e_in": 1.0, "e_shock": 1.0, "e_load_taken": 0.0, "eg_max_fraction": 0.99}) == []


def test_energies_figure_draws_the_line_the_balance_closes_on(ds):
    """Truth: eq. (11): the plotted E_g + E_p + D equals the plotted E_initial + E_shock to
    the residual, and the E_initial line is the energy at t = 0."""
    from granplate.figures.run import fig_energies

    fig = fig_energies(ds)
    lines = {ln.get_gid(): ln.get_ydata() for ax in fig.axes for ln in ax.get_lines()}
    e_in, total = lines["energy:input"], lines["energy:total"]
    ref = np.max(np.abs(e_in))
    assert np.max(np.abs(total - e_in)) <= 1e-6 * ref
    assert np.allclose(lines["energy:initial"], ds.attrs["E_initial"], rtol=0, atol=0)
    assert np.allclose(e_in - lines["energy:shock"], ds.attrs["E_initial"], rtol=1e-12)
    assert np.max(lines["fraction:total"]) <= 1.0 + 1e-6
    import matplotlib.pyplot as plt

    plt.close(fig)


def test_fractions_panel_says_the_load_took_energy_back(ds):
    """Panel (b) names the energy its fractions are of, and the work the load took back."""
    from granplate.figures.run import fig_energies
    from granplate.results.analysis import load_work

    fig = fig_energies(ds)
    title = fig.axes[1].get_title(loc="left")
    taken = load_work(ds.E_shock.values)[1][-1]
    assert "the energy put in" in title and f"it took {taken:.3g} J back" in title
    import matplotlib.pyplot as plt

    plt.close(fig)


def test_drive_and_gravity_work_count_as_energy_put_in():
    """Truth: eq. (11) with gravity and drives, E_p + E_g + D = E_0 + E_shock + E_gravity +
    E_drive: the summary's shares are of that sum (none above 1), its table names it E_in,
    and the energies figure's input line is what the stored and dissipated energies add up to."""
    import warnings
    from pathlib import Path

    import granplate as gp
    from granplate.cli import format_summary, reference_name
    from granplate.figures.run import energy_curves

    s = gp.load_scenario(str(Path(__file__).parents[1] / "docs" / "examples" / "driven-chain.toml"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ds = gp.simulate(s, t_end=1e-4, progress=False)
    summ = gp.summary(ds)
    assert summ["e_drive"] > 0.0 and summ["e_gravity"] != 0.0
    assert summ["e_in"] == pytest.approx(summ["e_shock"] + summ["e_initial"] + summ["e_gravity"] + summ["e_drive"])
    assert reference_name(summ) == "E_in" and "E_drive, work of the drives" in format_summary(summ)
    residual = summ["energy_residual_max"]
    assert max(summ["eg_max_fraction"], summ["dissipated_fraction"]) <= 1.0 + residual
    curves = energy_curves(ds)
    gap = np.abs(curves["total"][1] - curves["input"][1]).max()
    assert gap <= 2 * residual * np.abs(curves["input"][1]).max()
