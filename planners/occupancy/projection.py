"""2-D projections of the voxel occupancy map of seed 002 §2.1: the height map and per-column occupancy.

The seed's information map is a Sobel gradient of the "occupancy map" E seen from above; for a survey E is the
sensed seabed: per north–east column, the depth of the shallowest occupied voxel (the seabed, or the top of an
object standing on it). The grids here use the sample convention of `planners.infomap` and
`planners.detection`: cell (i, j) is centred at (north0 + i·cell, east0 + j·cell).

>>> import numpy as np
>>> column_reduce(np.array([0.1, 0.2, 1.0]), np.zeros(3), np.array([5.0, 4.0, 7.0]), (0, 1), (0, 0), 1.0, "min")
array([[4.],
       [7.]])
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


def grid_shape(north_range: tuple[float, float], east_range: tuple[float, float], cell: float) -> tuple[int, int]:
    """Rows and columns of a grid whose samples run from the range starts to their ends in steps of `cell`."""
    if not cell > 0:
        raise ValueError(f"cell must be positive, got {cell}")
    rows = int(math.floor((north_range[1] - north_range[0]) / cell + 1e-9)) + 1
    cols = int(math.floor((east_range[1] - east_range[0]) / cell + 1e-9)) + 1
    if rows < 1 or cols < 1:
        raise ValueError(f"empty grid: north {north_range}, east {east_range}")
    return rows, cols


def column_reduce(north: Array, east: Array, values: Array, north_range: tuple[float, float],
                  east_range: tuple[float, float], cell: float, how: str) -> Array:
    """Reduce `values` per grid cell (`min` or `max`: NaN where empty; `sum`: 0 where empty)."""
    rows, cols = grid_shape(north_range, east_range, cell)
    i = np.floor((np.asarray(north) - north_range[0]) / cell + 0.5).astype(np.int64)
    j = np.floor((np.asarray(east) - east_range[0]) / cell + 0.5).astype(np.int64)
    inside = (i >= 0) & (i < rows) & (j >= 0) & (j < cols)
    flat = i[inside] * cols + j[inside]
    v = np.asarray(values, dtype=float)[inside]
    if how == "sum":
        return np.bincount(flat, weights=v, minlength=rows * cols).astype(float).reshape(rows, cols)
    if how == "min":
        grid = np.full(rows * cols, np.inf)
        np.minimum.at(grid, flat, v)
    elif how == "max":
        grid = np.full(rows * cols, -np.inf)
        np.maximum.at(grid, flat, v)
    else:
        raise ValueError(f"unknown reduction '{how}' (expected 'min', 'max' or 'sum')")
    grid[~np.isfinite(grid)] = np.nan
    return grid.reshape(rows, cols)
