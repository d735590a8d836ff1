"""Results layer: the xarray Dataset of a run, its analysis, exports and documents."""


def __getattr__(name: str):
    # the study commands import this package to register: xarray loads on first use
    if name in ("read", "summary", "to_dataset", "write"):
        from granplate.results import dataset

        return getattr(dataset, name)
    raise AttributeError(f"module 'granplate.results' has no attribute {name!r}")
