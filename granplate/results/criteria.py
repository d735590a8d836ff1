"""Criteria that judge a number of ours, and the one `Check` type they judge.

A *criterion* decides whether a value holds (`holds(value, reference)`) and writes its
own text (`text(reference)`), naming what it judges, so a report never types a threshold twice:

    >>> Within(0.02).holds(1.52e-2, 1.53e-2), Within(0.02).text()
    (True, 'within 2% of the paper's value')
    >>> Between(0.45, 0.60, percent=True, name="plate peak share").text()
    'plate peak share in [45%, 60%]'

A *check* is one number of ours against a reference under a criterion: a verification
case's comparison with a closed form, or a statement of the paper with our value
(granplate.paper.statements). Both are rendered by granplate.results.document.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any


def number_text(x: float, percent: bool = False) -> str:
    """A threshold as text: 2% for 0.02 when percent, else the shortest %g form."""
    return f"{100 * x:g}%" if percent else f"{x:g}"


def _finite(v: Any) -> bool:
    try:
        return math.isfinite(float(v))
    except (TypeError, ValueError):
        return False


@dataclass(frozen=True)
class Criterion:
    """Base of the criteria: `holds` says True / False (None: not judged); `text` the rule.

    kind, tolerance: the verification page's names for the rule ("rel", "abs", "max",
    "min", or the criterion's class name) and its bound.
    """

    def holds(self, value: Any, reference: float | None = None) -> bool | None:
        raise NotImplementedError

    def text(self, reference: float | None = None) -> str:
        raise NotImplementedError

    @property
    def kind(self) -> str:
        return type(self).__name__

    @property
    def tolerance(self) -> float:
        return math.nan

    def error(self, value: Any, reference: float | None = None) -> float:
        """The compared error measure (the value itself for a bound)."""
        try:
            return float(value)
        except (TypeError, ValueError):
            return math.nan

    def tolerance_text(self) -> str:
        """The rule in the short form of a table column."""
        return self.text()


def _q(name: str) -> str:
    return f"{name} " if name else ""


@dataclass(frozen=True)
class Within(Criterion):
    """|value - ref| <= tol |ref| (relative) or <= tol (absolute=True).

    ref is `of` when given, else the reference the check carries, which `against` names
    in the text (by default the paper's value).
    """

    tol: float
    of: float | None = None
    absolute: bool = False
    name: str = ""
    against: str = "the paper's value"

    def _ref(self, reference: float | None) -> float:
        return float(self.of if self.of is not None else reference)

    def error(self, value: Any, reference: float | None = None) -> float:
        ref = self._ref(reference)
        if self.absolute:
            return abs(float(value) - ref)
        return abs(float(value) - ref) / abs(ref) if ref != 0.0 else math.inf

    def holds(self, value: Any, reference: float | None = None) -> bool:
        err = self.error(value, reference)
        return _finite(value) and not math.isnan(err) and err <= self.tol

    def text(self, reference: float | None = None) -> str:
        of = self.against if self.of is None else f"{self.of:g}"
        size = f"{self.tol:g}" if self.absolute else number_text(self.tol, percent=True)
        return f"{_q(self.name)}within {size} of {of}"

    @property
    def kind(self) -> str:
        return "abs" if self.absolute else "rel"

    @property
    def tolerance(self) -> float:
        return float(self.tol)

    def tolerance_text(self) -> str:
        return f"{self.tol:.1e} (abs.)" if self.absolute else f"{self.tol:.1e}"


@dataclass(frozen=True)
class Bound(Criterion):
    """value compared with a fixed bound: op one of "<", "<=", ">", ">="."""

    bound: float
    op: str = "<"
    percent: bool = False
    name: str = ""

    def __post_init__(self) -> None:
        if self.op not in ("<", "<=", ">", ">="):
            raise ValueError(f"op = {self.op!r}: allowed <, <=, >, >=")

    def holds(self, value: Any, reference: float | None = None) -> bool:
        if not _finite(value):
            return False
        v, b = float(value), float(self.bound)
        return {"<": v < b, "<=": v <= b, ">": v > b, ">=": v >= b}[self.op]

    def text(self, reference: float | None = None) -> str:
        return f"{_q(self.name)}{self.op} {number_text(self.bound, self.percent)}"

    @property
    def kind(self) -> str:
        return {"<=": "max", ">=": "min"}.get(self.op, self.op)

    @property
    def tolerance(self) -> float:
        return float(self.bound)

    def tolerance_text(self) -> str:
        if self.op == "<=":
            return f"ours <= {self.bound:.1e}"
        if self.op == ">=":
            return f"ours >= {self.bound:g}"
        return f"ours {self.op} {self.bound:g}"


def Below(bound: float, name: str = "", percent: bool = False) -> Bound:  # noqa: N802 - reads as a criterion
    """value < bound."""
    return Bound(bound, "<", percent, name)


def Above(bound: float, name: str = "", percent: bool = False) -> Bound:  # noqa: N802
    """value > bound."""
    return Bound(bound, ">", percent, name)


def AtMost(bound: float, name: str = "", percent: bool = False) -> Bound:  # noqa: N802
    """value <= bound."""
    return Bound(bound, "<=", percent, name)


def AtLeast(bound: float, name: str = "", percent: bool = False) -> Bound:  # noqa: N802
    """value >= bound."""
    return Bound(bound, ">=", percent, name)


@dataclass(frozen=True)
class Between(Criterion):
    """lo <= value <= hi (value < hi when upper_open)."""

    lo: float
    hi: float
    upper_open: bool = False
    percent: bool = False
    name: str = ""

    def holds(self, value: Any, reference: float | None = None) -> bool:
        if not _finite(value):
            return False
        v = float(value)
        return self.lo <= v and (v < self.hi if self.upper_open else v <= self.hi)

    def text(self, reference: float | None = None) -> str:
        lo, hi = number_text(self.lo, self.percent), number_text(self.hi, self.percent)
        return f"{_q(self.name)}in [{lo}, {hi}{')' if self.upper_open else ']'}"


@dataclass(frozen=True)
class Increasing(Criterion):
    """A sequence of values strictly increasing; with nan_is_never a NaN ("never") counts
    as later than any number, but the first value must be a number."""

    nan_is_never: bool = False
    name: str = ""

    def holds(self, value: Any, reference: float | None = None) -> bool:
        seq = [float(v) for v in value]
        if self.nan_is_never:
            if not seq or math.isnan(seq[0]):
                return False
            seq = [math.inf if math.isnan(v) else v for v in seq]
        return all(a < b for a, b in zip(seq, seq[1:]))

    def text(self, reference: float | None = None) -> str:
        never = " ('never' counts as the latest)" if self.nan_is_never else ""
        return f"{self.name + ': ' if self.name else ''}strictly increasing{never}"

    def error(self, value: Any, reference: float | None = None) -> float:
        return math.nan


@dataclass(frozen=True)
class Item(Criterion):
    """A criterion applied to one entry of a sequence value."""

    index: int
    criterion: Criterion

    def holds(self, value: Any, reference: float | None = None) -> bool | None:
        return self.criterion.holds(value[self.index], reference)

    def text(self, reference: float | None = None) -> str:
        return self.criterion.text(reference)


@dataclass(frozen=True)
class AllOf(Criterion):
    """Every part holds; the text joins the parts' texts with "and"."""

    parts: tuple[Criterion, ...]

    def holds(self, value: Any, reference: float | None = None) -> bool | None:
        verdicts = [p.holds(value, reference) for p in self.parts]
        return None if any(v is None for v in verdicts) else all(verdicts)

    def text(self, reference: float | None = None) -> str:
        return " and ".join(p.text(reference) for p in self.parts)


@dataclass(frozen=True)
class AtMostSetting(Criterion):
    """value <= the reference the check carries, a setting of the runs called `setting`."""

    setting: str
    name: str = ""

    def holds(self, value: Any, reference: float | None = None) -> bool:
        return _finite(value) and reference is not None and float(value) <= float(reference)

    def text(self, reference: float | None = None) -> str:
        value = "" if reference is None else f" = {reference:g}"
        return f"{_q(self.name)}<= {self.setting}{value}"


@dataclass(frozen=True)
class ReportedOnly(Criterion):
    """Shown, not judged (holds is None)."""

    def holds(self, value: Any, reference: float | None = None) -> None:
        return None

    def text(self, reference: float | None = None) -> str:
        return "reported, not judged"


@dataclass(frozen=True)
class Check:
    """One value of ours judged against a reference under a criterion.

    quantity: what is compared; unit ("-" for none); reference: the true or published
    value (None when the criterion needs none); source: where it comes from; ours: our
    value (a number or a sequence; None: not measured); criterion; why: the reason for
    the criterion; judged: False to show ours without a verdict (e.g. a run made with a
    scheme the criterion does not apply to). Display texts (the report's columns):
    reference_text, ours_text, ratio (ours / reference where meaningful), note, key.
    """

    quantity: str
    unit: str
    reference: float | None
    source: str
    ours: Any
    criterion: Criterion
    why: str = ""
    judged: bool = True
    reference_text: str = ""
    ours_text: str = ""
    ratio: float | None = None
    key: str = ""

    @property
    def holds(self) -> bool | None:
        """True / False, or None when not judged or not measured."""
        if self.ours is None or not self.judged:
            return None
        h = self.criterion.holds(self.ours, self.reference)
        return None if h is None else bool(h)

    @property
    def passed(self) -> bool:
        """Whether the check holds (a NaN, a missing or an unjudged value never passes)."""
        return self.holds is True

    @property
    def error(self) -> float:
        """The criterion's error measure (see Criterion.error)."""
        return self.criterion.error(self.ours, self.reference) if self.ours is not None else math.nan

    @property
    def kind(self) -> str:
        return self.criterion.kind

    @property
    def tolerance(self) -> float:
        return self.criterion.tolerance

    @property
    def rule(self) -> str:
        """The criterion's text, with the reason in parentheses when there is one."""
        text = self.criterion.text(self.reference)
        return f"{text} ({self.why})" if self.why else text

    def as_dict(self) -> dict:
        """Plain dict (for JSON): the fields, kind, tolerance, error and passed."""
        return {
            "quantity": self.quantity,
            "unit": self.unit,
            "reference": self.reference,
            "source": self.source,
            "ours": self.ours,
            "tolerance": self.tolerance,
            "why": self.why,
            "kind": self.kind,
            "error": float(self.error),
            "passed": bool(self.passed),
        }


def criterion_of_kind(kind: str, tolerance: float) -> Criterion:
    """The criterion of a verification check kind: "rel" / "abs" (Within), "max" (AtMost),
    "min" (AtLeast). ValueError for another kind."""
    if kind == "rel":
        return Within(tolerance)
    if kind == "abs":
        return Within(tolerance, absolute=True)
    if kind == "max":
        return AtMost(tolerance)
    if kind == "min":
        return AtLeast(tolerance)
    raise ValueError(f"unknown check kind {kind!r}: allowed rel, abs, max, min")
