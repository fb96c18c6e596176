"""3D segment lines of a stereo pair (seed 000 §3.1 step 3.2): edges found in the left image, their end points
matched along the epipolar rows of the right image by face-side correlation, and triangulated.

An edge of a face has the face on one side. Each side's patch is correlated along the epipolar row; at an
occluding edge only the nearer surface (the face the edge bounds) keeps the edge's disparity, so the face side is
the side whose patches match at the larger disparity (both sides agree on a convex edge between two faces, and
either serves). A segment is kept when both end points match on its face side with a clear correlation peak.

Edges are found by OpenCV's LSD (`cv2.createLineSegmentDetector`, in the main wheel since 4.5.1), keeping the
longest segments above a length.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from perception_plugins.multiview.patches import scan_row, side_grid
from perception_plugins.stereo.camera import RectifiedStereo
from perception_plugins.stereo.triangulation import triangulate

Array = NDArray[np.float64]
Image = NDArray[np.uint8]


@dataclass(frozen=True)
class Segment:
    """A 3D segment line of one view: end points in the left and right images and in the camera frame.

    `side` (+1 / −1) says where the face lies: along the left normal (−dy, dx) of the image direction from end 0
    to end 1, or opposite; `score` is each end point's stereo correlation."""

    uv_left: Array      # (2, 2)
    uv_right: Array     # (2, 2)
    points: Array       # (2, 3) camera frame (m)
    side: float
    score: Array        # (2,)

    @property
    def direction_2d(self) -> Array:
        d = self.uv_left[1] - self.uv_left[0]
        return np.asarray(d / np.linalg.norm(d))

    @property
    def length(self) -> float:
        return float(np.linalg.norm(self.points[1] - self.points[0]))


def detect_edges(image: Image, min_length_px: float = 60.0, max_segments: int = 120,
                 mask: NDArray[np.uint8] | None = None) -> Array:
    """(N, 4) image segments (u1, v1, u2, v2) of at least `min_length_px`, longest first (LSD)."""
    lsd = cv2.createLineSegmentDetector(cv2.LSD_REFINE_STD)
    found = lsd.detect(np.ascontiguousarray(image))[0]
    if found is None:
        return np.zeros((0, 4))
    lines = found.reshape(-1, 4).astype(float)
    length = np.hypot(lines[:, 2] - lines[:, 0], lines[:, 3] - lines[:, 1])
    keep = length >= min_length_px
    if mask is not None:
        h, w = mask.shape[:2]
        for end in (0, 2):
            u = np.clip(np.rint(lines[:, end]).astype(int), 0, w - 1)
            v = np.clip(np.rint(lines[:, end + 1]).astype(int), 0, h - 1)
            keep &= mask[v, u] > 0
    lines, length = lines[keep], length[keep]
    return np.asarray(lines[np.argsort(-length)][:max_segments])


def match_end_points(left: Image, right: Image, uv: Array, side: float, d_min: float, d_max: float,
                     min_score: float = 0.7) -> tuple[Array, Array, bool]:
    """Disparities of a segment's two end points (2, 2 pixels) with the face on `side`: (disparities, scores,
    both matched)."""
    disparities, scores, ok = np.zeros(2), np.zeros(2), True
    for e in range(2):
        into = uv[1 - e] - uv[e]
        # The patch's side is defined for the direction end 0 → end 1; seen from end 1 the normal flips.
        grid = side_grid(uv[e], into, side if e == 0 else -side)
        peak = scan_row(left, right, grid, d_min, d_max, min_score)
        disparities[e], scores[e] = peak.shift, peak.score
        ok &= peak.ok
    return disparities, scores, bool(ok)


def segment_from_disparities(geometry: RectifiedStereo, uv: Array, disparities: Array, side: float,
                             scores: Array) -> Segment | None:
    """Triangulate a segment from its left end points and their disparities."""
    uv_r = uv - np.column_stack([disparities, np.zeros(2)])
    cloud = triangulate(geometry, uv, uv_r)
    if len(cloud) != 2:
        return None
    return Segment(np.asarray(uv, dtype=float), uv_r, cloud.points_cam, float(side), np.asarray(scores))


def stereo_segments(left: Image, right: Image, geometry: RectifiedStereo, *, min_length_px: float = 60.0,
                    min_length_m: float = 0.1, max_range: float = 10.0, min_range: float = 0.5,
                    min_score: float = 0.7, mask: NDArray[np.uint8] | None = None,
                    max_segments: int = 120) -> list[Segment]:
    """The 3D segment lines of a rectified pair (see the module docstring)."""
    d_min, d_max = geometry.disparity_range(min_range, max_range)
    out: list[Segment] = []
    for line in detect_edges(left, min_length_px, max_segments, mask):
        uv = line.reshape(2, 2)
        found = []
        for side in (1.0, -1.0):
            disp, scores, ok = match_end_points(left, right, uv, side, d_min, d_max, min_score)
            if ok:
                found.append((float(disp.mean()), float(scores.min()), side, disp, scores))
        if not found:
            continue
        # The nearer face owns the edge; within a pixel of disparity, the better correlated side.
        found.sort(key=lambda f: (-round(f[0]), -f[1]))
        _, _, side, disp, scores = found[0]
        seg = segment_from_disparities(geometry, uv, disp, side, scores)
        if seg is not None and seg.length >= min_length_m:
            out.append(seg)
    return out


__all__ = ["Segment", "detect_edges", "match_end_points", "segment_from_disparities", "stereo_segments"]
