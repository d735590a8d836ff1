"""The static precompression with driven granules and walls (docs/model.md section 3.12): the
truth is statics. A displacement or velocity drive holds its granule along its direction only,
a force drive holds nothing and loads its granule with its value at t = 0; so the supports'
reactions (the walls' and the held directions') balance the precompression, the force drives'
loads and the weight (Newton's third law over the assembly), and a column's overlaps are the
Hertz overlaps of the forces statics puts through them, the driven bead sliding to them."""

from __future__ import annotations

import numpy as np
import pytest

import granplate as gp
from granplate.errors import ScenarioError
from granplate.model.arrays import build_model
from granplate.model.static import contact_terms
from granplate.physics.contact import COEF_A

F0 = 10.0
R = 0.005
G = 9.81

HEAD = """
name = "driven-column"
dimension = 3
[gravity]
g = [0.0, 0.0, {g!r}]
[[walls]]
label = "floor"
normal = [0.0, 0.0, -1.0]
offset = 0.0
[[walls]]
label = "top"
normal = [0.0, 0.0, 1.0]
offset = {top!r}
[precompression]
target = "wall top"
force = {force!r}
mode = "{mode}"
[contact]
mu = 0.0
alpha_n = 0.0
[time]
t_end = 2e-6
dt_initial = 2e-8
dt_max = 2e-8
output_interval = 2e-7
field_interval = 2e-7
[solver]
scheme = "verlet"
"""


def column(count: int, drives: str, mode: str = "held", g: float = -G, floor: bool = True) -> gp.Scenario:
    """`count` steel beads b0, b1, ... standing on the floor along z, pressed by F0 from the top
    wall, with the [[drives]] text `drives`; g = 0: without gravity; floor False: without
    the floor."""
    beads = "".join(
        f'[[granules]]\nlabel = "b{k}"\nx = 0.0\ny = 0.0\nz = {R + 2 * R * k!r}\nradius = {R}\nmaterial = "steel"\n'
        for k in range(count)
    )
    text = HEAD.format(g=g, top=2 * R * count, force=F0, mode=mode) + beads + drives
    if not floor:
        text = text.replace('[[walls]]\nlabel = "floor"\nnormal = [0.0, 0.0, -1.0]\noffset = 0.0\n', "")
    if not floor or g == 0.0:
        text = text.replace(f"[gravity]\ng = [0.0, 0.0, {g!r}]\n", "")
    return gp.loads(text)


def drive(target: str, kind: str, direction, profile: str, **fields) -> str:
    """A [[drives]] entry's text."""
    extra = "".join(f"{k} = {v!r}\n" for k, v in fields.items())
    return (
        f'[[drives]]\ntarget = "{target}"\nkind = "{kind}"\ndirection = {list(map(float, direction))!r}\n'
        f'profile = "{profile}"\n{extra}'
    )


SIDEWAYS = drive("granule b2", "force", (1, 0, 0), "harmonic", amplitude=0.01, frequency=1000.0) + drive(
    "granule b3", "velocity", (0, 1, 0), "constant", value=0.0
)
FLOOR = drive("wall floor", "velocity", (0, 0, 1), "table", times=[0.0, 1e-4], values=[0.0, 0.001])


def static_forces(model):
    """The static state's granule-pair forces (i, j, N) and each wall's total force [N]."""
    g = model.granular
    x = model.initial_state[:, :3]
    (i, j, _, f, _, _, _), (_, _, wf, _, _, _, _) = contact_terms(x, 0.0, g, -1)
    walls = np.zeros(len(g.wall_load))
    np.add.at(walls, g.wall_w, wf)
    return (i, j, f), walls


@pytest.mark.parametrize("push", [0.0, 2.5])
def test_the_supports_carry_the_precompression_the_drives_loads_and_the_weight(push):
    """Five beads on a velocity-driven floor under a held top wall's 10 N, one bead pushed
    sideways by a harmonic force (0 at t = 0), one held sideways by a velocity drive, and
    (push > 0) the top bead pushed down by a constant force drive: the floor carries F0 +
    push + the weight to 1e-8 (the held bead, held across the load, carries none of it), the top
    wall F0, and every pair the weight above it plus F0 + push."""
    extra = drive("granule b4", "force", (0, 0, -1), "constant", value=push) if push else ""
    model = build_model(column(5, SIDEWAYS + FLOOR + extra))
    mass = model.granular.mass
    (i, j, f), walls = static_forces(model)
    floor, top = walls
    assert floor == pytest.approx(F0 + push + float(mass.sum()) * G, rel=1e-8)
    assert top == pytest.approx(F0, rel=1e-8)
    above = np.array([F0 + push + float(mass[max(a, b) :].sum()) * G for a, b in zip(i, j)])
    on = f > 0.0
    assert on.sum() == 4
    np.testing.assert_allclose(f[on], above[on], rtol=1e-8)
    x = model.initial_state[:, :3]
    np.testing.assert_allclose(x[:, :2], 0.0, atol=1e-15)  # nothing pushes sideways at t = 0


@pytest.mark.parametrize(
    "kind, direction, push",
    [("velocity", (1, 0, 0), 0.0), ("displacement", (0, 1, 0), 0.0), ("force", (0, 0, -1), 3.0)],
)
def test_a_bead_driven_across_the_column_slides_down_to_its_hertz_overlaps(kind, direction, push):
    """Two beads on the floor pressed by F0, the upper one (b1) driven along x or y (held
    there) or pushed down by a force drive of `push` [N]: b1 sinks by the floor's and the
    pair's Hertz overlaps, ((F0 + push + 2 m g) / A_w)^(2/3) + ((F0 + push + m g) / A)^(2/3)
    (statics along the column: the floor carries everything, the pair all but b0's weight),
    and does not move across it."""
    fields = {"value": push} if kind == "force" else {"value": 0.0}
    s = column(2, drive("granule b1", kind, direction, "constant", **fields), mode="frozen")
    model = build_model(s)
    g = model.granular
    m = float(g.mass[0])
    a_w = float(g.wall_coef[0, COEF_A])
    a_p = float(g.pair_coef[0, COEF_A])
    sink = ((F0 + push + 2 * m * G) / a_w) ** (2 / 3) + ((F0 + push + m * G) / a_p) ** (2 / 3)
    x = model.initial_state[:, :3]
    assert x[1, 2] - 3 * R == pytest.approx(-sink, rel=1e-8)
    np.testing.assert_allclose(x[1, :2], 0.0, atol=1e-15)
    if kind == "force":  # the run starts there: the drive's displacement counts from the static state
        ds = gp.simulate(s, progress=False)
        assert abs(float(ds.drive_displacement.isel(time=0).values[0])) <= 1e-15


def test_a_bead_held_along_the_column_carries_the_force_and_the_floor_only_the_bead_below():
    """The same two beads, b1 held along z by a velocity drive: the top wall's F0 goes into
    b1's drive, b1 stays where it is, b0 rests on the floor under its own weight, (m g / A_w)^(2/3)
    deep, clear of b1."""
    model = build_model(column(2, drive("granule b1", "velocity", (0, 0, 1), "constant", value=0.0), mode="frozen"))
    g = model.granular
    m = float(g.mass[0])
    (_, _, f), (floor, top) = static_forces(model)
    x = model.initial_state[:, :3]
    assert x[1, 2] == 3 * R
    assert floor == pytest.approx(m * G, rel=1e-8)
    assert top == pytest.approx(F0, rel=1e-8)
    assert np.all(f == 0.0)
    assert x[0, 2] - R == pytest.approx(-((m * G / float(g.wall_coef[0, COEF_A])) ** (2 / 3)), rel=1e-8)


def test_a_force_driven_bead_is_no_support():
    """Without a floor under it, a column whose only other body is a force-driven bead gives
    the precompression no path to a support: refused naming precompression.target before
    minimising."""
    s = column(2, drive("granule b0", "force", (0, 0, 1), "constant", value=1.0), floor=False)
    with pytest.raises(ScenarioError) as e:
        build_model(s)
    assert e.value.field == "precompression.target"


SIDE = """
[[walls]]
label = "left"
normal = [0.0, -1.0, 0.0]
offset = {r!r}
[[walls]]
label = "right"
normal = [0.0, 1.0, 0.0]
offset = {r!r}
[[drives]]
target = "wall left"
kind = "force"
direction = [0.0, 1.0, 0.0]
profile = "constant"
value = {push!r}
mass = {mass!r}
"""


def test_a_force_driven_wall_rests_where_its_force_at_t0_is_carried():
    """One bead on the floor under the top wall's F0, squeezed sideways by a piston (a
    force-driven wall pushing with 2 N) against a fixed wall: at rest the fixed side wall
    carries the piston's 2 N, the bead sits (2 N / A_w)^(2/3) towards it, the piston 2 (2 N /
    A_w)^(2/3) in from where it started (both overlaps), the floor carries F0; the run starts
    there and nothing moves (the piston's displacement stays below 1e-12 m)."""
    push = 2.0
    s = column(1, SIDE.format(r=R, push=push, mass=0.01), g=0.0)
    model = build_model(s)
    g = model.granular
    _, (floor, top, left, right) = static_forces(model)
    a_w = float(g.wall_coef[0, COEF_A])
    side = (push / a_w) ** (2 / 3)
    assert (floor, top) == (pytest.approx(F0, rel=1e-8), pytest.approx(F0, rel=1e-8))
    assert (left, right) == (pytest.approx(push, rel=1e-8), pytest.approx(push, rel=1e-8))
    assert model.initial_state[0, 1] == pytest.approx(side, rel=1e-8)
    assert float(g.wall_geo[g.wall_w == 2, 3][0]) == pytest.approx(R - 2 * side, rel=1e-8)
    ds = gp.simulate(s, progress=False)
    assert np.max(np.abs(ds.drive_displacement.sel(drive="wall left").values)) <= 1e-12


def test_a_column_between_the_target_and_a_piston_has_no_support():
    """The floor made a piston (a force drive pushing up with F0): the column has no fixed
    support, refused naming precompression.target."""
    floor = drive("wall floor", "force", (0, 0, 1), "constant", value=F0, mass=0.01)
    with pytest.raises(ScenarioError) as e:
        build_model(column(2, floor, g=0.0))
    assert e.value.field == "precompression.target"


def test_a_sideways_push_at_t0_on_a_column_is_refused_naming_the_drive():
    """A constant sideways force on a bead of a straight column has no frictionless static
    equilibrium (no support reacts sideways): refused naming that drive's entry, not a minimiser's
    'no equilibrium' after its iterations."""
    drives = FLOOR + drive("granule b2", "force", (1, 0, 0), "constant", value=0.5)
    with pytest.raises(ScenarioError) as e:
        build_model(column(4, drives))
    assert e.value.field == "drives[1]" and "0.5 N no support can react" in str(e.value)
