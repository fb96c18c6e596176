"""Stage 2 (seed 000 §3.2.2): a view's segment lines and corners recognised in a working pair with H_work_view.

For each model segment, both end points are moved into CS^work with stage 1's transform and projected into the
working left image. The end point's face-side patch of the model image is laid onto the working image through the
same transform (each patch pixel back-projected at the end point's depth, moved and projected: this carries the
change of heading, altitude and perspective that the seed handles with the compass), then searched within a small
radius for the best zero-mean correlation (ZNCC is insensitive to the lighting's gain and offset). A confirmed end
point is matched along its epipolar row in the working right image, near the disparity the transform predicts, and
triangulated. A segment is recognised when both end points are; a corner when both of its segments are, its
points then computed from the recognised lines.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mission.geometry import invert, transform_points
from perception_plugins.multiview.corners import corner_points
from perception_plugins.multiview.model import ViewModel
from perception_plugins.multiview.patches import sample, scan_row, search_2d, side_grid, texture
from perception_plugins.stereo.camera import RectifiedStereo, backproject, project

Array = NDArray[np.float64]
Image = NDArray[np.uint8]


@dataclass(frozen=True)
class LineMatch:
    """Recognised segments of one view: model indices, their end points in CS^view and CS^work (k, 2, 3), the
    working left pixels (k, 2, 2) and correlations (k, 2); recognised corners with their points (c, 3, 3)."""

    segments: NDArray[np.int64]
    view_points: Array
    work_points: Array
    work_uv: Array
    scores: Array
    corners: NDArray[np.int64]
    corner_view_points: Array
    corner_work_points: Array


@dataclass(frozen=True)
class LineSettings:
    radius_px: int = 6
    min_score: float = 0.7
    disparity_window: float = 8.0


def _recognise_end(view: ViewModel, seg_index: int, end: int, T_work_view: Array, work_left: Image,
                   work_right: Image, geo: RectifiedStereo, settings: LineSettings
                   ) -> tuple[Array, Array, float] | None:
    seg = view.segments[seg_index]
    into = seg.uv_left[1 - end] - seg.uv_left[end]
    grid_m = side_grid(seg.uv_left[end], into, seg.side if end == 0 else -seg.side)
    ref = sample(view.left, grid_m)
    if texture(ref) < 2.0:
        return None
    z = float(seg.points[end, 2])
    grid_w = project(geo.K, transform_points(T_work_view, backproject(view.K, grid_m, np.full(len(grid_m), z))))
    shift, score, ok = search_2d(ref, work_left, grid_w, settings.radius_px, settings.min_score)
    if not ok:
        return None
    grid_w = grid_w + shift
    predicted = transform_points(T_work_view, seg.points[end:end + 1])[0]
    uv = project(geo.K, predicted[None])[0] + shift
    d_pred = float(geo.disparity(predicted[2]))
    peak = scan_row(work_left, work_right, grid_w, d_pred - settings.disparity_window,
                    d_pred + settings.disparity_window, settings.min_score)
    if not peak.ok:
        return None
    zw = geo.depth(peak.shift)
    point = backproject(geo.K, uv[None], np.atleast_1d(zw))[0]
    return point, uv, score


def recognise_lines(view: ViewModel, T_view_work: Array, work_left: Image, work_right: Image,
                    geo: RectifiedStereo, settings: LineSettings | None = None) -> LineMatch:
    """Stage 2 for one view (see the module docstring); `T_view_work` is stage 1's transform."""
    settings = settings or LineSettings()
    T_work_view = invert(T_view_work)
    found: dict[int, tuple[Array, Array, Array]] = {}
    for i in range(len(view.segments)):
        ends = []
        for e in (0, 1):
            r = _recognise_end(view, i, e, T_work_view, work_left, work_right, geo, settings)
            if r is None:
                break
            ends.append(r)
        if len(ends) == 2:
            found[i] = (np.array([ends[0][0], ends[1][0]]), np.array([ends[0][1], ends[1][1]]),
                        np.array([ends[0][2], ends[1][2]]))
    idx = np.array(sorted(found), dtype=np.int64)
    corners, cv, cw = [], [], []
    for k, c in enumerate(view.corners):
        a, b = c.segments
        if a in found and b in found:
            corners.append(k)
            cv.append(view.corner_points(k))
            cw.append(corner_points(found[a][0], c.ends[0], found[b][0], c.ends[1]))
    return LineMatch(idx, view.segment_points()[idx].reshape(-1, 2, 3),
                     np.array([found[i][0] for i in idx]).reshape(-1, 2, 3),
                     np.array([found[i][1] for i in idx]).reshape(-1, 2, 2),
                     np.array([found[i][2] for i in idx]).reshape(-1, 2),
                     np.array(corners, dtype=np.int64), np.array(cv).reshape(-1, 3, 3),
                     np.array(cw).reshape(-1, 3, 3))


__all__ = ["LineMatch", "LineSettings", "recognise_lines"]
