"""Shortened runs of the six presets, made once per test session and shared by the
figure, report and export tests (importable because pytest puts tests/ on sys.path)."""

from __future__ import annotations

import functools

import xarray as xr

#: Long enough for the wave to reach the plate in the steel cases (~0.08 ms).
T_END = 1e-4


@functools.lru_cache(maxsize=None)
def short_results(t_end: float = T_END) -> dict[str, xr.Dataset]:
    """preset name -> result Dataset of a run shortened to t_end [s] (do not modify: copy)."""
    import granplate as gp
    from granplate.setup.presets import preset, preset_names

    return {name: gp.simulate(preset(name), t_end=t_end, progress=False) for name in preset_names()}
