"""The information map of seed 002 §2.1: I = B ∗ G, where G is the Sobel gradient magnitude of the
occupancy/height map E and B a Gaussian whose σ is the vehicle's navigation uncertainty.

Man-made objects change height faster than the seabed around them, so they score high; agents weight their
surveys and detections with it. The gradient is returned in metres of height per metre (the raw Sobel kernels of
the seed, divided by 8·cell), so that thresholds do not depend on the grid.

>>> import numpy as np
>>> E = np.zeros((40, 40)); E[15:25, 15:25] = 2.0           # a 2 m box on a flat seabed, 1 m cells
>>> I = information_map(E, cell=1.0, nav_sigma_m=1.0)
>>> bool(I[15, 20] > 10 * I[2, 2] + 0.1), float(I[2, 2])   # edges light up; flat far field stays zero
(True, 0.0)
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

Array = NDArray[np.float64]


def fill_unknown(grid: Array) -> tuple[Array, NDArray[np.bool_]]:
    """Replace NaN (unobserved) cells by their nearest observed value; returns (filled, known mask)."""
    known = np.isfinite(grid)
    if known.all() or not known.any():
        return np.nan_to_num(grid, nan=0.0), known
    _, (ii, jj) = ndimage.distance_transform_edt(~known, return_indices=True)
    return grid[ii, jj], known


def sobel_gradient(grid: Array, cell: float) -> Array:
    """G = sqrt(Gx² + Gy²) with the seed's 3×3 Sobel kernels, scaled to height change per metre."""
    gx = ndimage.sobel(grid, axis=1, mode="nearest")
    gy = ndimage.sobel(grid, axis=0, mode="nearest")
    return np.asarray(np.hypot(gx, gy) / (8.0 * cell))


def information_map(height: Array, cell: float, nav_sigma_m: float) -> Array:
    """I = B ∗ G on a height (or occupancy) map; unobserved cells (NaN) score zero.

    `height` is any map whose steps mark structure: heights above the seabed, or depths (the sign does not
    matter to a gradient magnitude). `nav_sigma_m` is the horizontal 1σ navigation error: the blur spreads each
    edge over the area where it may truly lie.
    """
    filled, known = fill_unknown(np.asarray(height, dtype=float))
    gradient = sobel_gradient(filled, cell)
    sigma_cells = max(nav_sigma_m / cell, 0.0)
    info = ndimage.gaussian_filter(gradient, sigma=sigma_cells, mode="nearest") if sigma_cells > 0 else gradient
    info[~known] = 0.0
    return np.asarray(info)
