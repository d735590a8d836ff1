"""`granplate bench --solid`'s row: a build in a fresh process reports its dofs, modes and
the first clamped frequency; Leissa's closed form as the bench writes it."""

from __future__ import annotations

import math

import pytest

from granplate.bench.solid import bench_solid, format_rows, leissa_frequency


def test_leissa_frequency_closed_form():
    """f1 = 35.99 / a^2 sqrt(D / (rho h)) / 2 pi for steel, a = 0.1 m, h = 2 mm."""
    D = 200e9 * 0.002**3 / (12 * (1 - 0.3**2))
    assert leissa_frequency(0.1, 0.002) == pytest.approx(35.99 / 0.01 * math.sqrt(D / (7850 * 0.002)) / (2 * math.pi))


def test_bench_row_of_a_tiny_plate():
    """An 8 x 8 x 1 hex20 plate: dofs, a mode, the top face's z dofs and a table row."""
    row = bench_solid("hex20", (8, 8, 1), (0.1, 0.1, 0.002), residual=True, max_frequency=5e3)
    assert "failed" not in row and "refused" not in row, row
    assert (
        row["n_dofs"] > 0 and row["n_modes"] >= 1 and row["n_surface"] == 161
    )  # 7 x 7 corners + 112 mid-sides off the clamps
    assert row["f1_hz"] == pytest.approx(leissa_frequency(0.1, 0.002), rel=0.06)
    assert "| hex20 | 8 x 8 x 1 |" in format_rows([row], accuracy=True)


def test_plates_in_space_are_the_solid_rows(monkeypatch):
    """`bench --plates --dimension 3` runs the solid's table (the plate rows in space)."""
    from granplate import cli
    from granplate.bench import solid

    seen = []
    monkeypatch.setattr(solid, "main", lambda args: seen.append(args.plates) or 0)
    assert cli.main(["bench", "--plates", "--dimension", "3"]) == 0
    assert seen == [True]
