"""The paper's statements as data: what it says, where, its value, how ours is measured
and the criterion that judges it (docs/model.md section 8).

Each `Statement` is one record; `judge(statement, results)` turns it into a
granplate.results.criteria.Check with our value, computed from the result Datasets
(through granplate.results.analysis), never typed in. Only the paper's values are
constants here; every threshold lives in a criterion, which writes its own text.

    >>> checks = [judge(s, {"bare-plate": ds0, "steel-r1": ds1, ...}) for s in STATEMENTS]
    >>> checks[0].ours_text, checks[0].holds
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import xarray as xr

from granplate.results import analysis as an
from granplate.results.criteria import (
    Above,
    AllOf,
    AtMostSetting,
    Below,
    Between,
    Check,
    Criterion,
    Increasing,
    Item,
    ReportedOnly,
    Within,
)
from granplate.results.dataset import scenario_of

Results = dict[str, xr.Dataset]

PAPER_E_BARE = 1.53e-2  # J, Sec. 3
PAPER_E_STEEL = 7.48e-4  # J, Sec. 3
PAPER_VM_BARE = 350e6  # Pa, Sec. 3 ("~350 MPa")
PAPER_VM_STEEL = 80e6  # Pa, Sec. 3 ("~80 MPa")
PAPER_SHARE_STEEL_R05 = 0.40  # Sec. 3.2, "as much as 40%"
PAPER_SHARE_PTFE = 0.10  # Sec. 3.2, "about 10%"

#: What the paper says of each case's plate share (Sec. 3, 3.1, 3.2).
PAPER_SHARES = {
    "steel-r1": "a little over 50%",
    "steel-r05": "as much as 40%",
    "ptfe-r05": "about 10%",
    "ptfe-r05-moderate": "between weak and strong",
    "ptfe-r05-weak": "almost none",
}

#: The three shock intensities of Fig. 8, weak to strong.
INTENSITIES = ("ptfe-r05-weak", "ptfe-r05-moderate", "ptfe-r05")


@dataclass(frozen=True)
class Measured:
    """What a metric returns: the value the criterion judges (a number or a sequence),
    ours as text, and judged = False when the criterion does not apply to these runs;
    reference: a reference taken from the runs (e.g. a solver setting), if any."""

    value: object
    text: str
    judged: bool = True
    reference: float | None = None


@dataclass(frozen=True)
class Statement:
    """One statement of the paper: key, text, source (section / figure), the paper's
    value as stated, its number (for the ratio column, None if it has none), the runs the
    metric needs, the metric `metric(*datasets) -> Measured`, the criterion and why it
    was chosen (shown after the criterion's own text)."""

    key: str
    text: str
    source: str
    paper: str
    paper_value: float | None
    needs: tuple[str, ...]
    metric: Callable[..., Measured]
    criterion: Criterion
    why: str = ""


def _pct(x: float) -> str:
    return f"{100 * x:.1f}%"


def _mpa(x: float) -> str:
    return f"{x / 1e6:.1f} MPa"


def e_shock(ds: xr.Dataset) -> float:
    """The shock energy put in by the end of the run [J]."""
    return float(ds["E_shock"].values[-1])


def max_von_mises(ds: xr.Dataset) -> float:
    """The largest von Mises stress of the run [Pa]."""
    return float(ds["max_von_mises"].max())


def _peak(ds: xr.Dataset) -> float:
    return an.plate_share(ds)["peak"]


# --------------------------------------------------------------------------------------
# The metrics, one per statement
# --------------------------------------------------------------------------------------
def _energy(ds):
    v = e_shock(ds)
    return Measured(v, f"{v:.3e} J")


def _stress(ds):
    v = max_von_mises(ds)
    return Measured(v, _mpa(v))


def _share(ds):
    v = _peak(ds)
    return Measured(v, _pct(v))


def _vm_reduction(bare, steel):
    v = max_von_mises(steel) / max_von_mises(bare)
    return Measured(v, f"{v:.2f}")


def _energy_reduction(bare, steel):
    v = e_shock(bare) / e_shock(steel)
    return Measured(v, f"{v:.1f}x")


def _size_effect(r1, r05):
    a, b = _peak(r1), _peak(r05)
    return Measured(b / a, f"{_pct(b)} vs {_pct(a)} (ratio {b / a:.2f})")


def _similar_input(r1, r05):
    v = e_shock(r05) / e_shock(r1)
    return Measured(v, f"{v:.3f}")


def _ptfe_vs_steel(steel, ptfe):
    a, b = _peak(steel), _peak(ptfe)
    return Measured(b / a, f"{b / a:.2f} ({_pct(b)} / {_pct(a)})")


def _column_one(steel, ptfe):
    a, b = an.column_kinetic_share(steel)[0], an.column_kinetic_share(ptfe)[0]
    return Measured((a, b), f"{_pct(b)} of the kinetic energy (steel: {_pct(a)})")


def _slower(steel, ptfe):
    a, b = an.arrival_time(steel), an.arrival_time(ptfe)
    fa, fb = ("never" if math.isnan(x) else f"{x * 1e3:.3f} ms" for x in (a, b))
    return Measured((a, b), f"{fb} vs {fa}")


def _strain(steel, ptfe):
    a, b = float(steel["max_eps_yy"].max()), float(ptfe["max_eps_yy"].max())
    return Measured(b / a, f"{b:.2e} vs {a:.2e} (ratio {b / a:.2f})")


def _intensity(which: str, sep: str) -> Callable[..., Measured]:
    def metric(*runs):
        s = [an.plate_share(d)[which] for d in runs]
        return Measured(tuple(s), sep.join(_pct(x) for x in s))

    return metric


def _weak(weak):
    v = _peak(weak)
    return Measured(v, f"plate peak {_pct(v)}")


def _vertical(r1, r05):
    a, b = an.vertical_kinetic_share(r1), an.vertical_kinetic_share(r05)
    return Measured((a, b), f"{_pct(b)} vs {_pct(a)}")


def _lambda(steel):
    labels = [str(c) for c in steel["contact"].values]
    idx = [labels.index(c) for c in ("A", "B", "C") if c in labels]
    v = float(steel["local_map_modulus"].values[:, idx].max())
    if scenario_of(steel).solver.scheme != "paper":
        # criterion (8) is the stability limit of the paper's fixed-point iteration only
        return Measured(
            v,
            f"max abs(lambda) = {v:.1f} with the implicit scheme (Newton: stable for any "
            'abs(lambda), not judged; solver.scheme = "paper" keeps it < 1)',
            judged=False,
        )
    return Measured(v, f"max abs(lambda) = {v:.3f}")


def _plate_share(ds):
    s = an.plate_share(ds)
    return Measured(s["peak"], f"{_pct(s['peak'])} / {_pct(s['final'])}")


def _energy_balance(*runs):
    worst = max(an.max_energy_residual(d) for d in runs)
    tol = min(float(scenario_of(d).solver.energy_tol) for d in runs)
    return Measured(worst, f"max |residual| = {worst:.1e}", reference=tol)


# --------------------------------------------------------------------------------------
# The records, in the table's order
# --------------------------------------------------------------------------------------
_FIG8 = "Sec. 3.2, Fig. 8"
_INCREASING = "weak < moderate < strong"

#: Every statement of the table, in its order (the plate-share rows and the energy
#: balance are appended per run by `statements_for`).
STATEMENTS: tuple[Statement, ...] = (
    Statement(
        "bare_e_shock",
        "Shock energy put into the bare plate",
        "Sec. 3, Fig. 2a",
        "1.53e-2 J",
        PAPER_E_BARE,
        ("bare-plate",),
        _energy,
        Within(0.02),
        "the paper gives 3 digits",
    ),
    Statement(
        "bare_vm",
        "Max von Mises stress, bare plate",
        "Sec. 3, Fig. 3a",
        "~350 MPa",
        PAPER_VM_BARE,
        ("bare-plate",),
        _stress,
        Within(0.15),
        "read off a figure, '~'",
    ),
    Statement(
        "steel_e_shock",
        "Shock energy put into the granules (steel, R2 = R1)",
        "Sec. 3, Fig. 2b",
        "7.48e-4 J",
        PAPER_E_STEEL,
        ("steel-r1",),
        _energy,
        Within(0.02),
    ),
    Statement(
        "steel_vm",
        "Max von Mises stress with granules (steel, R2 = R1)",
        "Sec. 3, Fig. 3b",
        "~80 MPa",
        PAPER_VM_STEEL,
        ("steel-r1",),
        _stress,
        Within(0.15),
    ),
    Statement(
        "vm_reduction",
        "Granules cut the max von Mises stress far below the bare plate's",
        "Sec. 3, Fig. 3a-b",
        f"{PAPER_VM_STEEL / PAPER_VM_BARE:.2f} (80 / 350 MPa)",
        PAPER_VM_STEEL / PAPER_VM_BARE,
        ("bare-plate", "steel-r1"),
        _vm_reduction,
        Below(0.5, "with-granules / bare"),
    ),
    Statement(
        "energy_reduction",
        "Granules cut the energy put in ('close to two orders of magnitude')",
        "Sec. 3",
        f"{PAPER_E_BARE / PAPER_E_STEEL:.1f}x",
        PAPER_E_BARE / PAPER_E_STEEL,
        ("bare-plate", "steel-r1"),
        _energy_reduction,
        Above(10, "bare / with-granules"),
    ),
    Statement(
        "steel_r1_peak",
        "Plate energy peak, steel R2 = R1: 'a little over 50%' of E_shock",
        "Sec. 3, Figs. 3c, 4a",
        "> 50%",
        0.50,
        ("steel-r1",),
        _share,
        Between(0.45, 0.60, percent=True, name="plate peak share"),
        "read off a figure",
    ),
    Statement(
        "size_effect",
        "Plate peak share slightly lower with R2 = 0.5 R1 than with R2 = R1",
        "Sec. 3.1, Fig. 4a-b",
        "slightly below (< 1)",
        None,
        ("steel-r1", "steel-r05"),
        _size_effect,
        Between(0.7, 1.0, upper_open=True, name="ratio of peaks"),
    ),
    Statement(
        "steel_r05_peak",
        "Steel R2 = 0.5 R1: 'as much as 40%' reaches the plate (peak)",
        "Sec. 3.2",
        "40%",
        PAPER_SHARE_STEEL_R05,
        ("steel-r05",),
        _share,
        Within(0.15),
    ),
    Statement(
        "similar_input",
        "Both intruder sizes take in a similar shock energy",
        "Sec. 3.1",
        "similar (1)",
        1.0,
        ("steel-r1", "steel-r05"),
        _similar_input,
        Within(0.05, of=1.0, name="ratio"),
    ),
    Statement(
        "ptfe_share",
        "PTFE R2 = 0.5 R1: 'about 10%' eventually reaches the plate (peak)",
        "Sec. 3.2, Fig. 5a",
        "~10%",
        PAPER_SHARE_PTFE,
        ("ptfe-r05",),
        _share,
        Within(0.3),
        "'about'",
    ),
    Statement(
        "ptfe_vs_steel",
        "PTFE intruders let a much smaller share reach the plate than steel ones",
        "Sec. 3.2, Figs. 4b, 5a",
        "0.25 (10% / 40%)",
        PAPER_SHARE_PTFE / PAPER_SHARE_STEEL_R05,
        ("steel-r05", "ptfe-r05"),
        _ptfe_vs_steel,
        Below(0.5, "PTFE peak / steel peak"),
    ),
    Statement(
        "column_one",
        "PTFE: the energy stays in column 1 (granules 1-5)",
        "Sec. 3.2, Figs. 5c, 6b",
        "mostly in column 1",
        None,
        ("steel-r05", "ptfe-r05"),
        _column_one,
        AllOf(
            (
                Item(1, Above(0.5, "PTFE: column 1's share of the granular kinetic energy over the run", percent=True)),
                Increasing(name="that share, steel then PTFE"),
            )
        ),
    ),
    Statement(
        "slower",
        "PTFE: slower waves (later arrival at the plate)",
        "Sec. 3.2, Fig. 6",
        "slower",
        None,
        ("steel-r05", "ptfe-r05"),
        _slower,
        Increasing(nan_is_never=True, name="time for the plate to hold 1% of E_shock, steel then PTFE"),
    ),
    Statement(
        "strain",
        "PTFE: max eps_yy in the plate significantly reduced",
        "Sec. 3.2, Fig. 7",
        "significantly lower",
        None,
        ("steel-r05", "ptfe-r05"),
        _strain,
        Below(0.5, "PTFE / steel"),
    ),
    Statement(
        "intensity_peak",
        "The plate's share grows with the shock intensity (peak share)",
        _FIG8,
        _INCREASING,
        None,
        INTENSITIES,
        _intensity("peak", " < "),
        Increasing(name="peak shares"),
    ),
    Statement(
        "intensity_mean",
        "The plate's share grows with the shock intensity (time-mean share)",
        _FIG8,
        _INCREASING,
        None,
        INTENSITIES,
        _intensity("mean", ", "),
        Increasing(name="time-averaged shares"),
    ),
    Statement(
        "intensity_final",
        "The plate's share grows with the shock intensity (share at t_end)",
        _FIG8,
        _INCREASING,
        None,
        INTENSITIES,
        _intensity("final", ", "),
        Increasing(name="shares at the last output"),
    ),
    Statement(
        "weak",
        "Weak shock: almost all the energy stays in the granules",
        "Sec. 3.2, Fig. 8a",
        "almost all",
        None,
        ("ptfe-r05-weak",),
        _weak,
        Below(0.05, "plate peak share", percent=True),
    ),
    Statement(
        "vertical",
        "Smaller intruders scatter more kinetic energy into vertical motion",
        "Sec. 3.1, Fig. 4c-d",
        "more with R2 = 0.5 R1",
        None,
        ("steel-r1", "steel-r05"),
        _vertical,
        Increasing(name="vertical share of the granular kinetic energy over the run, R2 = R1 then R2 = 0.5 R1"),
    ),
    Statement(
        "lambda",
        "Frictional local maps stay contractive at contacts A, B, C",
        "App. A, Fig. A.1",
        "abs(lambda) < 1",
        None,
        ("steel-r1",),
        _lambda,
        Below(1.0, "max abs(lambda) over the run"),
    ),
) + tuple(
    Statement(
        f"share_{name}",
        f"Plate share of E_shock, {name}: peak / at t_end",
        "Figs. 3-5, 8",
        f"{said} / not stated",
        None,
        (name,),
        _plate_share,
        ReportedOnly(),
    )
    for name, said in PAPER_SHARES.items()
)

#: The energy balance of eq. (11), judged over every run given.
ENERGY_BALANCE = Statement(
    "energy_balance",
    "Energy balance E_p + E_g + D = E_shock (eq. 11), every run",
    "Sec. 2, eq. 11",
    "holds at every step",
    None,
    (),
    _energy_balance,
    AtMostSetting("solver.energy_tol", "max |residual| of every run"),
)


def judge(s: Statement, results: Results) -> Check:
    """The statement's Check: our value from the runs it needs (all runs given for the
    energy balance), or "not run (names)" with no verdict when one is missing."""
    missing = [n for n in s.needs if n not in results]
    runs = [results[n] for n in s.needs if n in results] if s.needs else list(results.values())
    if missing or not runs:
        return Check(
            s.text,
            "",
            s.paper_value,
            s.source,
            None,
            s.criterion,
            s.why,
            reference_text=s.paper,
            ours_text=f"not run ({', '.join(missing)})",
            key=s.key,
        )
    m = s.metric(*runs)
    reference = m.reference if m.reference is not None else s.paper_value
    ratio = (
        float(m.value) / s.paper_value
        if s.paper_value is not None and isinstance(m.value, float) and m.judged and s.paper_value != 0
        else None
    )
    return Check(
        s.text,
        "",
        reference,
        s.source,
        m.value,
        s.criterion,
        s.why,
        judged=m.judged,
        reference_text=s.paper,
        ours_text=m.text,
        ratio=ratio,
        key=s.key,
    )


def statements(results: Results) -> list[Check]:
    """The comparison table (docs/model.md section 8) computed from the result datasets.

    results: preset name -> Dataset. A statement whose runs are missing shows
    "not run" with no verdict; the plate-share rows appear for the runs given that have
    granules, then the energy balance of every run.
    """
    rows = [judge(s, results) for s in STATEMENTS if not s.key.startswith("share_")]
    shares = {s.needs[0]: s for s in STATEMENTS if s.key.startswith("share_")}
    for name, ds in results.items():
        if an.has_granules(ds):
            s = shares.get(name) or Statement(
                f"share_{name}",
                f"Plate share of E_shock, {name}: peak / at t_end",
                "Figs. 3-5, 8",
                "not stated / not stated",
                None,
                (name,),
                _plate_share,
                ReportedOnly(),
            )
            rows.append(judge(s, results))
    rows.append(judge(ENERGY_BALANCE, results))
    return rows
