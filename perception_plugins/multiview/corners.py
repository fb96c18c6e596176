""""Corner" macro-elements (seed 000 §3.1 step 3.3, §3.2.2): two segment lines of one face sharing a vertex.

Two segments form a corner when an end of each lies within a few pixels (and centimetres) of the other's, their
directions differ by at least `min_angle_deg` from parallel, and each lies on the other's face side (both bound
the same face, which removes the ambiguity between faces meeting at one vertex). The vertex is the midpoint of
the closest points of the two 3D lines; a corner's characteristic points are the vertex and one point on each
arm, `ARM_M` from it (seed eq. 4 counts the points that fix a corner's position).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from perception_plugins.multiview.segments import Segment

Array = NDArray[np.float64]

ARM_M = 0.2


@dataclass(frozen=True)
class Corner:
    """Segments (a, b) of a view and the end of each at the vertex."""

    segments: tuple[int, int]
    ends: tuple[int, int]


def corner_points(points_a: Array, end_a: int, points_b: Array, end_b: int, arm: float = ARM_M) -> Array:
    """(3, 3): the vertex (closest points of the two lines, averaged) and a point `arm` along each arm."""
    pa, pb = np.asarray(points_a, dtype=float), np.asarray(points_b, dtype=float)
    da = pa[1 - end_a] - pa[end_a]
    db = pb[1 - end_b] - pb[end_b]
    da, db = da / np.linalg.norm(da), db / np.linalg.norm(db)
    w0 = pa[end_a] - pb[end_b]
    b = float(da @ db)
    d, e = float(da @ w0), float(db @ w0)
    den = 1.0 - b * b
    s, t = ((b * e - d) / den, (e - b * d) / den) if den > 1e-9 else (0.0, 0.0)
    vertex = 0.5 * ((pa[end_a] + s * da) + (pb[end_b] + t * db))
    return np.array([vertex, vertex + arm * da, vertex + arm * db])


def find_corners(segments: list[Segment], max_gap_px: float = 15.0, max_gap_m: float = 0.08,
                 min_angle_deg: float = 30.0) -> list[Corner]:
    """Corners among one view's segments (see the module docstring)."""
    out: list[Corner] = []
    cos_max = np.cos(np.radians(min_angle_deg))
    for i, a in enumerate(segments):
        for j in range(i + 1, len(segments)):
            b = segments[j]
            if abs(float(a.direction_2d @ b.direction_2d)) > cos_max:
                continue
            best: tuple[float, int, int] | None = None
            for ea in (0, 1):
                for eb in (0, 1):
                    gap = float(np.linalg.norm(a.uv_left[ea] - b.uv_left[eb]))
                    if gap <= max_gap_px and np.linalg.norm(a.points[ea] - b.points[eb]) <= max_gap_m:
                        if best is None or gap < best[0]:
                            best = (gap, ea, eb)
            if best is None:
                continue
            _, ea, eb = best
            if _on_face(a, ea, b, eb) and _on_face(b, eb, a, ea):
                out.append(Corner((i, j), (ea, eb)))
    return out


def _on_face(a: Segment, end_a: int, b: Segment, end_b: int) -> bool:
    """True when b's far end lies on a's face side."""
    t = a.direction_2d
    normal = a.side * np.array([-t[1], t[0]])
    return bool(normal @ (b.uv_left[1 - end_b] - a.uv_left[end_a]) > 0)


__all__ = ["ARM_M", "Corner", "corner_points", "find_corners"]
