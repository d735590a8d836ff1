"""Results layer: the xarray Dataset of a run, its analysis, exports and documents."""

from granplate.results.dataset import read, summary, to_dataset, write  # noqa: F401
