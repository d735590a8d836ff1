"""A result states its dimension (attribute `dimension`, 2 or 3) and its readers take it from
there, not from which variables it holds; older results without it: 3 where they hold z."""

from __future__ import annotations

import numpy as np
import xarray as xr

from granplate.figures.run import granule_speeds
from granplate.results.dataset import dimension_of


def _result(dimension: int | None) -> xr.Dataset:
    v = xr.DataArray(np.full((2, 3), 3.0), dims=("time", "granule"))
    ds = xr.Dataset({"vx": v, "vy": v * 0 + 4.0, "vz": v * 0 + 12.0, "z": v * 0})
    if dimension is not None:
        ds.attrs["dimension"] = dimension
    return ds


def test_the_attribute_decides_the_dimension_and_the_speeds():
    """|v| = 5 m/s in the plane (3, 4), 13 m/s in space (3, 4, 12), whatever variables exist;
    without the attribute the depth z says space."""
    assert dimension_of(_result(2)) == 2 and dimension_of(_result(3)) == 3
    assert dimension_of(_result(None)) == 3 and dimension_of(_result(None).drop_vars("z")) == 2
    np.testing.assert_allclose(granule_speeds(_result(2)), 5.0)
    np.testing.assert_allclose(granule_speeds(_result(3)), 13.0)
