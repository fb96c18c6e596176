"""Ray triangulation of matched points on a rectified pair, with per-point depth uncertainty (seed 002 §3.1).

Seed 000 §3.1 builds its 3D points "using the ray triangulation method". On a rectified pair the two rays of a
match meet at depth Z = f·B / (d + doffs) (d = u_l − u_r); the point is the left ray through (u_l, v_l) at that
depth: X = (u_l − cx)·Z / fx, Y = (v_l − cy)·Z / fy. A disparity error σ_d (pixels) gives, to first order,
σ_Z = Z²·σ_d / (f·B): stereo depth gets worse with the square of the range.

>>> from perception_plugins.stereo.camera import RectifiedStereo
>>> geo = RectifiedStereo(1000.0, 1000.0, 600.0, 450.0, 0.25, (1200, 900))
>>> cloud = triangulate(geo, np.array([[700.0, 450.0]]), np.array([[630.0, 450.0]]), sigma_d=0.5)
>>> cloud.points_cam.round(6).tolist(), round(float(cloud.sigma_z[0]), 6)
([[0.357143, 0.0, 3.571429]], 0.02551)
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from perception_plugins.stereo.camera import RectifiedStereo

Array = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class Cloud:
    """A triangulated cloud in the left camera frame (OpenCV axes), one row per matched point."""

    points_cam: Array
    """(N, 3) points (m)."""
    sigma_z: Array
    """(N,) one-sigma depth uncertainty (m) from the disparity uncertainty."""
    uv_left: Array
    """(N, 2) pixels in the (rectified) left image."""
    uv_right: Array
    """(N, 2) pixels in the (rectified) right image."""
    descriptors: NDArray[np.generic] = field(default_factory=lambda: np.zeros((0, 0), np.float32))
    """(N, D) left-image descriptors (empty when none were given)."""

    def __len__(self) -> int:
        return int(self.points_cam.shape[0])

    @property
    def disparity(self) -> Array:
        return np.asarray(self.uv_left[:, 0] - self.uv_right[:, 0])

    def subset(self, keep: NDArray[np.bool_] | NDArray[np.int_]) -> Cloud:
        descriptors = self.descriptors[keep] if len(self.descriptors) == len(self) else self.descriptors
        return Cloud(self.points_cam[keep], self.sigma_z[keep], self.uv_left[keep], self.uv_right[keep], descriptors)


def depth_sigma(depth: Array, sigma_d: float, fB: float) -> Array:
    """σ_Z = Z²·σ_d / (f·B).

    >>> float(depth_sigma(np.array([4.0]), 0.5, 250.0)[0])
    0.032
    """
    return np.asarray(np.asarray(depth, dtype=float) ** 2 * sigma_d / fB)


def triangulate(geometry: RectifiedStereo, uv_left: ArrayLike, uv_right: ArrayLike, sigma_d: float = 0.3,
                descriptors: NDArray[np.generic] | None = None, R_cam_rect: ArrayLike | None = None) -> Cloud:
    """Triangulate matches of a rectified pair into the left camera frame.

    `R_cam_rect` rotates rectified-camera coordinates back into the original left camera (the transpose of
    OpenCV's R1) when the pair was rectified here; rows with a non-positive d + doffs are dropped.
    """
    uv_l, uv_r = np.asarray(uv_left, dtype=float).reshape(-1, 2), np.asarray(uv_right, dtype=float).reshape(-1, 2)
    d = uv_l[:, 0] - uv_r[:, 0] + geometry.doffs
    keep = d > 0
    uv_l, uv_r, d = uv_l[keep], uv_r[keep], d[keep]
    z = geometry.fB / d
    points = np.column_stack([(uv_l[:, 0] - geometry.cx) * z / geometry.fx,
                              (uv_l[:, 1] - geometry.cy) * z / geometry.fy, z])
    if R_cam_rect is not None:
        points = points @ np.asarray(R_cam_rect, dtype=float).T
    desc = descriptors[keep] if descriptors is not None else np.zeros((0, 0), np.float32)
    return Cloud(points, depth_sigma(z, sigma_d, geometry.fB), uv_l, uv_r, desc)


__all__ = ["Cloud", "depth_sigma", "triangulate"]
