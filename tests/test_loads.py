"""The load kinds (granplate.model.loads) against closed forms: what each kind pushes, and
its shares of the shock, in the plane and in space."""

from __future__ import annotations

import math

import numpy as np
import pytest

from granplate.model import loads
from granplate.setup.load_checks import LOAD_KINDS, LOAD_RULES
from granplate.setup.scenario import Granule, Load, Scenario


def _column(dimension: int = 2, **load) -> Scenario:
    """Three equal spheres (R = 1 cm) in a row along x, and a fourth above the first."""
    gs = (
        Granule(x=0.01, y=0.05, radius=0.01, material="steel", label="a"),
        Granule(x=0.03, y=0.05, radius=0.01, material="steel", label="b"),
        Granule(x=0.05, y=0.05, radius=0.01, material="steel", label="c"),
        Granule(x=0.01, y=0.07, radius=0.01, material="steel", label="d"),
    )
    return Scenario(dimension=dimension, granules=gs, load=Load(**load))


def _arrays(s: Scenario) -> tuple[np.ndarray, np.ndarray]:
    pos = np.array([(g.x, g.y, g.z) for g in s.granules], float)
    return pos, np.array([g.radius for g in s.granules], float)


def test_every_kind_has_its_module_and_its_rules():
    """The registry of the arrays (model.loads.KINDS) and that of the rules (LOAD_RULES) name the same kinds."""
    assert set(loads.KINDS) == set(LOAD_RULES) == set(LOAD_KINDS)
    assert all(kind.name == name for name, kind in loads.KINDS.items())


def test_a_new_kind_is_its_module_and_one_rules_entry(monkeypatch):
    """A kind registered once (an entry of LOAD_RULES) is read from the module of its name,
    and a module whose KIND bears another name is refused, naming both."""
    import sys
    import types

    from granplate.setup.load_checks import LoadRules

    module = types.ModuleType("granplate.model.loads.pulse")
    module.KIND = loads.KINDS["none"]._replace(name="pulse")
    monkeypatch.setitem(sys.modules, "granplate.model.loads.pulse", module)
    monkeypatch.setitem(LOAD_RULES, "pulse", LoadRules((2, 3), lambda s: None))
    assert loads._kinds()["pulse"] is module.KIND
    module.KIND = loads.KINDS["none"]
    with pytest.raises(ImportError, match="pulse.KIND is named 'none'"):
        loads._kinds()


def test_line_load_pushes_column_one_with_the_closed_form_resultants():
    """A line load pushes the leftmost granules, each with int q dy and its moment over its
    diameter (paper eq. 12): a granule centred on the load's middle takes 2 L/pi sin(pi R/L) and no torque."""
    s = _column(kind="line", q0=1.0, y0=0.0, length=0.1)
    pos, r = _arrays(s)
    assert loads.loaded_labels(s) == ("a", "d")
    f, tq = loads.resultants(s, pos, r)
    length = 0.1
    # a: centred at y = L/2: F/q0 = int_{L/2-R}^{L/2+R} sin(pi y/L) dy = 2 L/pi sin(pi R/L)
    assert f[0, 0] == pytest.approx(2 * length / math.pi * math.sin(math.pi * 0.01 / length), rel=1e-12)
    assert tq[0, 2] == pytest.approx(0.0, abs=1e-15)
    assert tq[3, 2] != 0.0  # d is off the middle: a torque
    assert np.all(f[1:3] == 0.0) and np.all(f[:, 1:] == 0.0) and np.all(tq[:, :2] == 0.0)
    assert loads.amplitude(s) == 1.0 and loads.plate_edge(s) is None


def test_line_load_on_the_plate_pushes_no_granule():
    """Target "plate": the load presses the plate's edge (y0, L) and no granule."""
    s = _column(kind="line", target="plate", q0=2.0, y0=0.01, length=0.03)
    pos, r = _arrays(s)
    assert loads.plate_edge(s) == (0.01, 0.03)
    assert not loads.loaded_granules(s, pos, r).any()
    assert not np.any(loads.resultants(s, pos, r)[0])


def test_force_load_is_shared_equally_and_sums_to_the_force():
    """A force load: the granules furthest against its direction share it equally; the
    shares sum to the unit direction (total force = amplitude x direction), no torque."""
    d = (0.0, -3.0, 4.0)
    s = _column(dimension=3, kind="force", force=5.0, direction=d)
    pos, r = _arrays(s)
    # furthest against d = (0, -0.6, 0.8): the smallest s.d - R, i.e. the largest y (granule d)
    assert loads.loaded_labels(s) == ("d",)
    f, tq = loads.resultants(s, pos, r)
    assert f.sum(axis=0) == pytest.approx(np.array(d) / 5.0, abs=1e-15)
    assert not tq.any() and loads.amplitude(s) == 5.0
    along_x = _column(dimension=3, kind="force", force=5.0)
    f, _ = loads.resultants(along_x, *_arrays(along_x))
    assert loads.loaded_labels(along_x) == ("a", "d")
    assert f[[0, 3], 0] == pytest.approx([0.5, 0.5], abs=0) and f.sum() == pytest.approx(1.0, abs=1e-15)


def test_named_granules_take_the_load():
    """load.granules overrides the default choice, for either kind."""
    s = _column(dimension=3, kind="force", force=1.0, granules=("c",))
    assert loads.loaded_labels(s) == ("c",)
    s = _column(kind="line", granules=("b", "c"))
    assert loads.loaded_labels(s) == ("b", "c")


def test_no_load_pushes_nothing():
    """kind = "none": amplitude 0, nothing loaded, no resultants."""
    s = _column(kind="none")
    pos, r = _arrays(s)
    assert loads.amplitude(s) == 0.0 and loads.plate_edge(s) is None and not loads.loaded_labels(s)
    assert not np.any(loads.resultants(s, pos, r))
