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

from granplate.study.spec import Study, load_study, parse_study  # noqa: F401
from granplate.study.sweep import SweepReport, sweep  # noqa: F401
