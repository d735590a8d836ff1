"""Design studies: a grid (or sample) of changes to a base scenario, run on Dask.

- `spec`: the study file (base, [set], [parameters], [zip]) and its designs;
- `design`: one design's identity, run and on-disk record;
- `table`: the study's table (results.nc, results.csv);
- `sweep`: the Dask driver (warm-up, as_completed, resume);
- `cli`: `granplate sweep` (and `granplate optimize`).

    >>> from granplate.study import load_study, sweep
    >>> report = sweep(load_study("study.toml"), "out", workers=2)
"""
from __future__ import annotations


def __getattr__(name: str):
    # the CLI imports this package to register `sweep`: Dask and xarray load on first use
    if name in ("Study", "load_study", "parse_study"):
        from granplate.study import spec
        return getattr(spec, name)
    if name in ("SweepReport", "sweep"):
        from granplate.study import sweep as sweep_module
        return getattr(sweep_module, name)
    raise AttributeError(f"module 'granplate.study' has no attribute {name!r}")
