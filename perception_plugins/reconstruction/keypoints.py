"""Characteristic-point sets proposed from a reconstructed mesh (seed 002 §3.1: characteristic points are corners a
Harris detector extracts well from above; seed 000: sets that fix the object's pose without ambiguity).

The mesh is seen from above as a height map over the seabed plane (the highest vertex in each cell); Harris
corners of that map are 3D corners of the object a down-looking camera will find. The strongest corners, spread
apart, are grouped into sets of `set_size` (4–6); a set is symmetric when a quarter or half turn about its centroid
maps it onto itself within `tolerance` (then the prior heading must choose, as the database says of such sets).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class PointSetProposal:
    points: Array
    """(k, 3) world points (north, east, depth)."""
    symmetric: bool


def height_map(vertices: Array, plane: Array, cell: float) -> tuple[Array, Array]:
    """(rows, cols) height above the plane depth = a·north + b·east + c of the highest vertex in each cell (0 where
    none), rows along north, and the (north, east) of cell (0, 0)."""
    height = plane[0] * vertices[:, 0] + plane[1] * vertices[:, 1] + plane[2] - vertices[:, 2]
    origin = vertices[:, :2].min(axis=0)
    ij = np.floor((vertices[:, :2] - origin) / cell).astype(np.int64)
    shape = tuple(int(s) for s in ij.max(axis=0) + 1)
    grid = np.zeros(shape)
    np.maximum.at(grid, (ij[:, 0], ij[:, 1]), np.maximum(height, 0.0))
    return grid, origin


def harris_corners(grid: Array, count: int, min_separation_cells: int = 5) -> NDArray[np.int64]:
    """(≤ count, 2) cells of the strongest Harris corners of a height map, strongest first, local maxima only."""
    response = cv2.cornerHarris(grid.astype(np.float32), blockSize=3, ksize=3, k=0.04)
    size = 2 * min_separation_cells + 1
    peaks = (response == cv2.dilate(response, np.ones((size, size), np.uint8))) & (response > 0.01 * response.max())
    cells = np.argwhere(peaks)
    order = np.argsort(-response[peaks])
    return np.asarray(cells[order][:count], dtype=np.int64)


def is_symmetric(points_2d: Array, tolerance: float) -> bool:
    """Whether a quarter, half or three-quarter turn about the centroid maps the points onto themselves.

    >>> is_symmetric(np.array([[0.0, 0], [2, 0], [2, 1], [0, 1]]), 0.05)
    True
    >>> is_symmetric(np.array([[0.0, 0], [2, 0], [2, 1], [0, 1], [0.4, 0.3]]), 0.05)
    False
    """
    centred = points_2d - points_2d.mean(axis=0)
    for angle in (np.pi / 2, np.pi, 3 * np.pi / 2):
        c, s = np.cos(angle), np.sin(angle)
        turned = centred @ np.array([[c, -s], [s, c]]).T
        gaps = np.linalg.norm(turned[:, None, :] - centred[None, :, :], axis=2).min(axis=1)
        if np.all(gaps < tolerance):
            return True
    return False


def propose_point_sets(vertices: Array, plane: Array, set_size: int = 5, sets: int = 2, cell: float = 0.05,
                       min_height: float = 0.1, tolerance: float = 0.1) -> list[PointSetProposal]:
    """Sets of `set_size` object corners (world frame) from the mesh's vertices, strongest corners first."""
    if not 4 <= set_size <= 6:
        raise ValueError(f"a characteristic-point set has 4 to 6 points, not {set_size}")
    grid, origin = height_map(vertices, plane, cell)
    cells = harris_corners(grid, set_size * sets * 2)
    cells = cells[grid[cells[:, 0], cells[:, 1]] >= min_height]  # corners of the object, not of the seabed
    north_east = origin + (cells + 0.5) * cell
    heights = grid[cells[:, 0], cells[:, 1]]
    depth = plane[0] * north_east[:, 0] + plane[1] * north_east[:, 1] + plane[2] - heights
    corners = np.column_stack([north_east, depth])
    proposals = []
    for k in range(sets):
        chosen = corners[k * set_size:(k + 1) * set_size]
        if len(chosen) < 4:
            break
        proposals.append(PointSetProposal(chosen, is_symmetric(chosen[:, :2], tolerance)))
    return proposals


__all__ = ["PointSetProposal", "harris_corners", "height_map", "is_symmetric", "propose_point_sets"]
