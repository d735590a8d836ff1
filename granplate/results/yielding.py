"""How close a run's contacts came to yield (docs/model.md section 3.6): the largest
Hertz peak pressure p0 (eq. P2) of every contact, from its largest overlap, and its ratio
to the yield onset 1.6 Y of the softer body (eq. P1), gathered by material pair.

A pair is labelled by its two materials, sorted ("ptfe-steel"), or by the granule's
material and "wall" / "plate" for the rigid bodies, which enter the contact law with the
granule's modulus and radius alone (E_k, R_k -> infinity, eq. 3) and so never yield: the
granule does. In space, a granule on one of an elastic body's rigid patches meets a rigid
body likewise (the 2D rigid layer's law); elsewhere on the body, E* and Y are of both
materials. The ratio is NaN where a Y it needs is unknown (summary: null).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from granplate.model.arrays import material_indices, normal_law_of
from granplate.physics.plastic import hertz_peak_pressure, limiting_pressure
from granplate.setup.materials import effective_modulus, softer_yield_strength
from granplate.solver.state import PARTNER_PLATE


class PairYield(NamedTuple):
    """The largest Hertz peak pressure of each material pair and where it was reached."""

    pair: tuple[str, ...]  # material-pair labels, sorted
    pressure: np.ndarray  # [Pa] the largest Hertz peak pressure p0 (eq. P2) at a contact of the pair
    ratio: np.ndarray  # [-] p0 / (1.6 Y) of the softer body (eq. P1); NaN where Y is unknown
    yield_strength: np.ndarray  # [Pa] Y of the softer body; NaN where unknown
    time: np.ndarray  # [s] when that contact reached its largest overlap
    contact: tuple[str, ...]  # the contact: "c1r1-c2r1", "c1r1-wall left" (its label, else its index), "c3r1-plate"
    law: tuple[str, ...]  # the pair's normal law ("hertz", "thornton", "johnson")


def contact_yield(model, peaks) -> list[tuple[str, float, float, float, float, str, str]]:
    """One (pair label, p0 [Pa], ratio [-], Y [Pa], time [s], contact label, law) per contact
    of `peaks` (solver.driver.ContactPeaks)."""
    s, mats, r, labels = model.scenario, model.materials, model.granular.radius, model.labels
    rows = []
    body = s.material(s.plate.material) if getattr(model, "solid", None) is not None else None  # an elastic solid
    for i, j, d, t in zip(peaks.granule, peaks.partner, peaks.delta_max, peaks.time):
        a = mats[i]
        if j == PARTNER_PLATE and body is not None:
            # a granule on a rigid patch meets a rigid body (the loop's law: E* of the granule alone)
            rigid = model.body_rigid is not None and bool(model.body_rigid[i])
            b = None if rigid else body
            e_star, r_star = effective_modulus(a, b), r[i]
            pair, who, law = f"{a.name}-plate", f"{labels[i]}-plate", normal_law_of(s, a.name, body.name)
            y = softer_yield_strength(a, b)
            p0 = hertz_peak_pressure(e_star, r_star, float(d))
            ratio = p0 / limiting_pressure(y) if y is not None else math.nan
            rows.append((pair, p0, ratio, math.nan if y is None else float(y), float(t), who, law))
            continue
        if j >= 0:
            b = mats[j]
            e_star, r_star = effective_modulus(a, b), r[i] * r[j] / (r[i] + r[j])
            pair, who, law = (
                "-".join(sorted((a.name, b.name))),
                f"{labels[i]}-{labels[j]}",
                normal_law_of(s, a.name, b.name),
            )
        else:
            e_star, r_star = effective_modulus(a, None), r[i]
            if j == PARTNER_PLATE:
                pair, who, law = f"{a.name}-plate", f"{labels[i]}-plate", normal_law_of(s, a.name, s.plate.material)
            else:
                w = -1 - j
                wall = s.walls[w]
                pair, who, law = (
                    f"{a.name}-wall",
                    f"{labels[i]}-wall {wall.label or w}",
                    normal_law_of(s, a.name, wall.material),
                )
        y = softer_yield_strength(a, b if j >= 0 else None)
        p0 = hertz_peak_pressure(e_star, r_star, float(d))
        ratio = p0 / limiting_pressure(y) if y is not None else math.nan
        rows.append((pair, p0, ratio, math.nan if y is None else float(y), float(t), who, law))
    return rows


def _rows(peaks, index):
    """The rows `index` (a mask or indices) of ContactPeaks `peaks`; a column it lacks
    (None) stays None."""
    return type(peaks)(*(None if a is None else np.asarray(a)[index] for a in peaks))


def pair_yield(model, peaks) -> PairYield:
    """The largest p0 of each material pair of the run (`contact_yield`), sorted by pair.
    The granule pairs, most of a large assembly's contacts, are taken by numpy: each pair
    of materials' largest p0 (its first contact in `peaks`' order), whose row
    `contact_yield` then makes, the same numbers as taking every contact's row."""
    on = peaks.partner >= 0
    rest, first = _rows(peaks, ~on), _rows(peaks, on)
    chosen = pair_maxima(model, first)
    picked = _rows(first, chosen)
    best: dict[str, tuple] = {}
    for row in contact_yield(model, picked) + contact_yield(model, rest):
        if row[0] not in best or row[1] > best[row[0]][1]:
            best[row[0]] = row
    rows = [best[k] for k in sorted(best)]
    col = list(zip(*rows)) if rows else [()] * 7
    return PairYield(
        pair=tuple(col[0]),
        pressure=np.array(col[1], float),
        ratio=np.array(col[2], float),
        yield_strength=np.array(col[3], float),
        time=np.array(col[4], float),
        contact=tuple(col[5]),
        law=tuple(col[6]),
    )


def pair_maxima(model, peaks) -> np.ndarray:
    """Indices into `peaks` (granule pairs only) of each pair of materials' contact of the
    largest Hertz peak pressure p0 = (2/pi) E* sqrt(delta / R*) (eq. P2, as
    `hertz_peak_pressure` computes it), the first of equals, ascending."""
    if not len(peaks.granule):
        return np.zeros(0, np.int64)
    kinds, kind = material_indices(model.materials)
    r = np.asarray(model.granular.radius, float)
    i, j = np.asarray(peaks.granule, np.int64), np.asarray(peaks.partner, np.int64)
    ki, kj = kind[i], kind[j]
    group = np.minimum(ki, kj) * len(kinds) + np.maximum(ki, kj)
    e_star = np.empty(len(i))
    for g in np.unique(group).tolist():
        e_star[group == g] = effective_modulus(kinds[g // len(kinds)], kinds[g % len(kinds)])
    ri, rj = r[i], r[j]
    p0 = 2.0 / math.pi * e_star * np.sqrt(np.asarray(peaks.delta_max, float) / (ri * rj / (ri + rj)))
    order = np.lexsort((-p0, group))  # by group, the largest p0 first, ties in peaks' order
    starts = np.flatnonzero(np.r_[True, group[order][1:] != group[order][:-1]])
    return np.sort(order[starts])


def largest(py: PairYield) -> tuple[float, float]:
    """(max_contact_pressure [Pa], yield_onset_ratio [-]) over the pairs: the largest p0
    (NaN: no contact touched) and the largest ratio over the pairs whose Y is known (NaN: none)."""
    p = float(py.pressure.max()) if len(py.pressure) else math.nan
    known = py.ratio[np.isfinite(py.ratio)]
    return p, float(known.max()) if len(known) else math.nan


def yield_warning(name: str, py: PairYield) -> str | None:
    """One line for the elastic (Hertz) pair whose contacts went furthest past the onset of
    yield (ratio > 1), naming the pair, the contact, the time, the ratio and the plastic law;
    None when no elastic contact passed it."""
    over = [k for k in range(len(py.pair)) if py.law[k] == "hertz" and py.ratio[k] > 1.0]
    if not over:
        return None
    k = max(over, key=lambda q: py.ratio[q])
    more = f" ({len(over) - 1} other pair(s) too)" if len(over) > 1 else ""
    return (
        f"{name}: Hertz contacts passed the onset of yield: pair {py.pair[k]}, contact {py.contact[k]} at "
        f"t = {py.time[k]:.4g} s, p0 = {py.pressure[k] / 1e6:.4g} MPa = {py.ratio[k]:.3g} x 1.6 Y "
        f"(Y = {py.yield_strength[k] / 1e6:.4g} MPa){more}. The elastic law no longer holds there; "
        f'contact.normal_law = "johnson" follows contacts that yield as measured (docs/model.md section '
        f'3.10; "thornton", section 3.6).'
    )
