"""Characteristic-point sets proposed from a reconstructed mesh (seed 002 §3.1: characteristic points are corners a
Harris detector extracts well from above; seed 000: sets that fix the object's pose without ambiguity).

The mesh is seen from above as a height map over the seabed plane (the highest vertex in each cell); Harris
corners of its outlines (on the log of the heights, so that a low frame's corner counts as much as a tall
column's) are 3D corners of the object a down-looking camera will find, each placed on the top face of its step.
The strongest corner and its nearest neighbours make a set of `set_size` (4–6; near, so that one view holds the
set), then the next strongest left and its neighbours; a set is symmetric when a quarter or half turn about its
centroid maps it onto itself within `tolerance` (then the prior heading must choose, as the database says of such
sets), and a farther corner replaces the last one when that breaks the symmetry.
"""

from __future__ import annotations

from collections.abc import Sequence
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
    none), rows along north, and the (north, east) of cell (0, 0). One-cell gaps (a mesh whose vertex spacing is
    near the cell, seen as stripes of empty cells) are closed with a 3 × 3 grey closing."""
    height = plane[0] * vertices[:, 0] + plane[1] * vertices[:, 1] + plane[2] - vertices[:, 2]
    origin = vertices[:, :2].min(axis=0)
    ij = np.floor((vertices[:, :2] - origin) / cell).astype(np.int64)
    shape = tuple(int(s) for s in ij.max(axis=0) + 1)
    grid = np.zeros(shape)
    np.maximum.at(grid, (ij[:, 0], ij[:, 1]), np.maximum(height, 0.0))
    closed = cv2.morphologyEx(grid.astype(np.float32), cv2.MORPH_CLOSE, np.ones((3, 3), np.uint8))
    return np.asarray(closed, dtype=float), origin


def harris_corners(grid: Array, count: int, min_separation_cells: int = 5, block_cells: int = 3,
                   relative: float = 0.01) -> NDArray[np.int64]:
    """(≤ count, 2) cells of the strongest Harris corners of a height map, strongest first, local maxima only."""
    response = cv2.cornerHarris(grid.astype(np.float32), blockSize=block_cells, ksize=3, k=0.04)
    size = 2 * min_separation_cells + 1
    peaks = (response == cv2.dilate(response, np.ones((size, size), np.uint8))) \
        & (response > relative * response.max())
    cells = np.argwhere(peaks)
    order = np.argsort(-response[peaks])
    return np.asarray(cells[order][:count], dtype=np.int64)


def step_image(grid: Array, step_m: float, min_height: float) -> Array:
    """The height map as a camera from above sees the object's outlines: log(1 + h / `step_m`), so that a step's
    strength follows its height's ratio (a 0.4 m frame on the seabed makes as strong an edge as a 3 m column on
    the frame), with the specks under `min_height` or smaller than 3 × 3 cells removed (noise of the fused surface,
    not structure)."""
    mask = cv2.morphologyEx((grid >= min_height).astype(np.uint8), cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))
    return np.asarray(np.where(mask > 0, np.log1p(np.maximum(grid, 0.0) / step_m), 0.0), dtype=float)


def convex_share(grid: Array, cells: NDArray[np.int64], radius_cells: int) -> Array:
    """For each cell, the share of the disc of `radius_cells` around it that lies on the high side of the step
    there (heights above the middle of the disc's lowest and highest): about 1/4 at a convex right-angled corner,
    1/2 on a straight edge or a wide curve (a column's rim), 3/4 in a concave corner.

    >>> grid = np.zeros((40, 40)); grid[10:, 10:] = 1.0
    >>> convex_share(grid, np.array([[10, 10], [25, 10]]), 6).round(2).tolist()
    [0.31, 0.56]
    """
    r = radius_cells
    dy, dx = np.mgrid[-r:r + 1, -r:r + 1]
    disc = (dy * dy + dx * dx) <= r * r
    padded = np.pad(grid, r, mode="edge")
    shares = []
    for row, col in cells:
        window = padded[row:row + 2 * r + 1, col:col + 2 * r + 1][disc]
        middle = 0.5 * (window.min() + window.max())
        shares.append(float(np.mean(window > middle)))
    return np.asarray(shares, dtype=float)


def group_sets(corners: Array, set_size: int, sets: int, tolerance: float) -> list[PointSetProposal]:
    """Disjoint sets of `set_size` corners (fewer, down to 4, when fewer are left), each the strongest remaining
    corner and its nearest neighbours (so a set fits one view); when those are symmetric, the farther candidates
    are tried in turn for the last place."""
    remaining = list(range(len(corners)))
    proposals: list[PointSetProposal] = []
    while len(proposals) < sets and len(remaining) >= 4:
        seed = remaining[0]
        near = sorted(remaining, key=lambda i: float(np.linalg.norm(corners[i, :2] - corners[seed, :2])))
        size = min(set_size, len(near))
        chosen = near[:size]
        symmetric = is_symmetric(corners[chosen, :2], tolerance)
        for alternative in near[size:size + 4]:
            if not symmetric:
                break
            trial = near[:size - 1] + [alternative]
            if not is_symmetric(corners[trial, :2], tolerance):
                chosen, symmetric = trial, False
        proposals.append(PointSetProposal(corners[chosen], symmetric))
        remaining = [i for i in remaining if i not in chosen]
    return proposals


def stable_points(clouds: Sequence[Array], radius: float = 0.05, min_views: int = 5,
                  separation: float = 0.3) -> Array:
    """Points a detector finds again and again (seed 002 §3.1: characteristic points are the ones the detector
    extracts well): of the views' points (world frame, one array a view), those with points of at least
    `min_views` views within `radius`, most-seen first, at least `separation` apart, each the median of its
    neighbours.

    >>> rng = np.random.default_rng(0)
    >>> views = [np.vstack([[[0, 0, 1], [2, 0, 1]] + rng.normal(0, 0.01, (2, 3)), rng.uniform(-5, 5, (3, 3))])
    ...          for _ in range(6)]
    >>> (np.round(stable_points(views), 1) + 0.0).tolist()
    [[0.0, 0.0, 1.0], [2.0, 0.0, 1.0]]
    """
    from scipy.spatial import cKDTree

    if not clouds or sum(len(c) for c in clouds) == 0:
        return np.zeros((0, 3))
    points = np.vstack([c for c in clouds if len(c)])
    view = np.concatenate([np.full(len(c), k) for k, c in enumerate(clouds) if len(c)])
    tree = cKDTree(points)
    neighbours = tree.query_ball_point(points, radius)
    seen = np.array([len(set(view[n].tolist())) for n in neighbours])
    chosen: list[int] = []
    for i in np.argsort(-seen, kind="stable"):
        if seen[i] < min_views:
            break
        if all(np.linalg.norm(points[i] - points[j]) > separation for j in chosen):
            chosen.append(int(i))
    return np.array([np.median(points[neighbours[i]], axis=0) for i in chosen]).reshape(-1, 3)


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
                       min_height: float = 0.1, tolerance: float = 0.1, step_m: float = 0.1,
                       separation_m: float = 0.3, max_convex_share: float = 0.36) -> list[PointSetProposal]:
    """Sets of `set_size` object corners (world frame) from the mesh's vertices: Harris corners of the height map's
    `step_image`, at least `separation_m` apart, each placed on the top of its step (the highest cell within
    `separation_m` / 2: the corner a camera from above sees is the top face's), convex (`convex_share` at most
    `max_convex_share`), grouped by `group_sets`."""
    if not 4 <= set_size <= 6:
        raise ValueError(f"a characteristic-point set has 4 to 6 points, not {set_size}")
    grid, origin = height_map(vertices, plane, cell)
    separation = max(1, int(round(separation_m / cell)))
    steps = step_image(grid, step_m, min_height)
    cells = harris_corners(steps, set_size * sets * 3, min_separation_cells=separation,
                           block_cells=max(3, separation | 1), relative=0.05)
    if len(cells) == 0:
        return []
    # Harris's window shifts its peaks off the corner; the sub-cell corner is where the outline's edges meet.
    xy = np.ascontiguousarray(cells[:, ::-1].astype(np.float32).reshape(-1, 1, 2))
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.01)
    reach = max(1, separation // 2)
    rc = cv2.cornerSubPix(steps.astype(np.float32), xy, (reach, reach), (-1, -1), criteria).reshape(-1, 2)[:, ::-1]
    at = np.clip(np.round(rc).astype(np.int64), 0, np.array(grid.shape) - 1)
    top = np.asarray(cv2.dilate(grid.astype(np.float32), np.ones((2 * reach + 1, 2 * reach + 1), np.uint8)), float)
    heights = top[at[:, 0], at[:, 1]]
    # A corner a camera finds from above is a convex one: a straight edge's bump or a column's rim is not.
    keep = (heights >= min_height) & (convex_share(grid, at, separation) <= max_convex_share)
    north_east = origin + (rc[keep].astype(float) + 0.5) * cell
    heights = heights[keep]
    depth = plane[0] * north_east[:, 0] + plane[1] * north_east[:, 1] + plane[2] - heights
    return group_sets(np.column_stack([north_east, depth]), set_size, sets, tolerance)


__all__ = ["PointSetProposal", "group_sets", "harris_corners", "height_map", "is_symmetric", "propose_point_sets",
           "stable_points", "step_image"]
