"""Trackable stereo features: well-spread corners in the left image, their right-image matches found by pyramidal
Lucas–Kanade along the rows of the rectified pair, and their triangulated points (`perception_plugins.stereo`).

Seed 003 matches the stereo pair with SURF and tracks across time with KLT; SURF is not in the OpenCV wheels, so the
stereo correspondences come from KLT too (Shi–Tomasi corners, LK left → right seeded with the expected disparity,
kept when the match stays on its row and the right → left check returns within `fb_tol` px).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from perception_plugins.stereo import RectifiedStereo, refine_disparities, triangulate

Array = NDArray[np.float64]
Image = NDArray[np.uint8]

LK_WINDOW = (21, 21)
LK_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 30, 0.01)


@dataclass(frozen=True, eq=False)
class StereoFeatures:
    """Features of one stereo pair: left pixels, right pixels on the same rows, points in the left camera."""

    uv_left: Array
    uv_right: Array
    points_cam: Array

    def __len__(self) -> int:
        return int(self.uv_left.shape[0])


def grid_corners(image: Image, count: int = 500, grid: tuple[int, int] | None = None,
                 mask: NDArray[np.uint8] | None = None, quality: float = 0.001, min_distance: float = 7.0,
                 border: int = 12) -> Array:
    """Up to `count` Shi–Tomasi corners spread over a grid (columns, rows) of cells: each cell keeps its strongest
    corners up to an equal share, so texture-rich corners of the image do not take all of them."""
    h, w = image.shape[:2]
    if grid is None:
        cols = max(1, round(np.sqrt(count * w / h / 12.0)))
        grid = (cols, max(1, round(count / 12.0 / cols)))
    m = np.zeros((h, w), np.uint8)
    m[border:h - border, border:w - border] = 255
    if mask is not None:
        m &= mask
    found = cv2.goodFeaturesToTrack(image, maxCorners=4 * count, qualityLevel=quality, minDistance=min_distance,
                                    mask=m, blockSize=5)
    if found is None:
        return np.zeros((0, 2))
    xy = found.reshape(-1, 2).astype(float)  # strongest first
    cell = (np.minimum((xy[:, 0] * grid[0] / w).astype(int), grid[0] - 1)
            + grid[0] * np.minimum((xy[:, 1] * grid[1] / h).astype(int), grid[1] - 1))
    order = np.argsort(cell, kind="stable")
    sorted_cell = cell[order]
    first = np.searchsorted(sorted_cell, sorted_cell, side="left")
    rank = np.empty(len(xy), dtype=int)
    rank[order] = np.arange(len(xy)) - first
    share = int(np.ceil(count / (grid[0] * grid[1])))
    keep = np.flatnonzero(rank < share)
    return np.asarray(xy[keep[:count]])


def lk(previous: Image, current: Image, points: Array, guess: Array | None = None, max_level: int = 3,
       window: tuple[int, int] = LK_WINDOW) -> tuple[Array, NDArray[np.bool_]]:
    """Pyramidal LK from `previous` to `current`, optionally from guessed positions; returns the tracked points and
    which succeeded and stayed inside the image."""
    if len(points) == 0:
        return np.zeros((0, 2)), np.zeros(0, dtype=bool)
    p0 = np.ascontiguousarray(points, dtype=np.float32).reshape(-1, 1, 2)
    flags = 0
    start: Any = None
    if guess is not None:
        start = np.ascontiguousarray(guess, dtype=np.float32).reshape(-1, 1, 2)
        flags = cv2.OPTFLOW_USE_INITIAL_FLOW
    p1, status, _ = cv2.calcOpticalFlowPyrLK(previous, current, p0, start, winSize=window, maxLevel=max_level,
                                             criteria=LK_CRITERIA, flags=flags)
    out = np.asarray(p1, dtype=float).reshape(-1, 2)
    h, w = current.shape[:2]
    ok = (status.reshape(-1) == 1) & (out[:, 0] >= 0) & (out[:, 0] <= w - 1) & (out[:, 1] >= 0) & (out[:, 1] <= h - 1)
    return out, ok


def stereo_match(left: Image, right: Image, uv_left: Array, geometry: RectifiedStereo,
                 disparity_guess: Array | float = 0.0, row_tol: float = 1.0, fb_tol: float = 0.5,
                 min_disparity: float = 0.5, min_ncc: float = 0.4) -> tuple[Array, NDArray[np.bool_]]:
    """Right-image positions of left pixels on a rectified pair by LK, seeded at u − `disparity_guess`; a match
    counts when it stays within `row_tol` px of its row, has at least `min_disparity` px of disparity and the
    right → left track returns within `fb_tol` px."""
    guess = np.asarray(uv_left, dtype=float).copy()
    guess[:, 0] -= disparity_guess
    uv_r, ok = lk(left, right, uv_left, guess, max_level=4)
    back, ok_back = lk(right, left, uv_r, uv_left, max_level=1)
    d = uv_left[:, 0] - uv_r[:, 0] + geometry.doffs
    ok &= ok_back & (np.abs(uv_r[:, 1] - uv_left[:, 1]) <= row_tol) & (d >= min_disparity)
    ok &= np.linalg.norm(back - uv_left, axis=1) <= fb_tol
    uv_r[:, 1] = uv_left[:, 1]
    # The two windows must look alike (zero-mean normalised correlation): LK also "converges" on featureless
    # noise (a sediment cloud, a lamp failure), where no texture backs the match.
    _, _, score, _ = refine_disparities(left, right, uv_left, uv_r, half=4, search=2, min_score=min_ncc)
    ok &= score >= min_ncc
    return uv_r, ok


def stereo_features(left: Image, right: Image, geometry: RectifiedStereo, count: int = 500,
                    mask: NDArray[np.uint8] | None = None, disparity_guess: float = 0.0,
                    max_depth: float | None = None) -> StereoFeatures:
    """Detect spread corners on the left image, match them on the right, triangulate (left camera frame)."""
    uv_l = grid_corners(left, count, mask=mask)
    uv_r, ok = stereo_match(left, right, uv_l, geometry, disparity_guess)
    cloud = triangulate(geometry, uv_l[ok], uv_r[ok])
    keep = np.ones(len(cloud), dtype=bool) if max_depth is None else cloud.points_cam[:, 2] <= max_depth
    return StereoFeatures(cloud.uv_left[keep], cloud.uv_right[keep], cloud.points_cam[keep])


__all__ = ["StereoFeatures", "grid_corners", "lk", "stereo_features", "stereo_match"]
