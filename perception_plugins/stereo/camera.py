"""Pinhole cameras, stereo calibration and rectification (seed 002 §3.1: stereo pairs of a down-looking camera).

Conventions follow OpenCV: pixel (u, v) with u to the right and v down, pixel centres at integer coordinates; camera
x right, y down, z along the optical axis; the left camera is the stereo frame. A calibration's `R`, `T` map left
camera coordinates to right camera coordinates (X_r = R·X_l + T), as `cv2.stereoRectify` wants them, so a right
camera at +B along the left camera's x has T = (−B, 0, 0).

`RectifiedStereo` is the geometry that matching and triangulation work in: both images share rows, focal length
f and principal row cy; the right principal point may sit `doffs` pixels right of the left one (Middlebury), so
depth is Z = f·B / (d + doffs) with d = u_l − u_r.

>>> import numpy as np
>>> geo = RectifiedStereo.from_K(np.array([[1000.0, 0, 599.5], [0, 1000.0, 449.5], [0, 0, 1]]), 0.25, (1200, 900))
>>> float(geo.depth(np.array([50.0]))[0]), geo.disparity_range(min_range=1.0, max_range=8.0)
(5.0, (31.25, 250.0))
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]
RemapTable = NDArray[np.integer[Any] | np.floating[Any]]


def project(K: Array, points_cam: ArrayLike, dist: ArrayLike | None = None) -> Array:
    """(N, 3) camera points → (N, 2) pixels; with `dist`, OpenCV's distortion model applies.

    >>> project(np.array([[100.0, 0, 50], [0, 100.0, 40], [0, 0, 1]]), [[0.2, -0.1, 2.0]]).tolist()
    [[60.0, 35.0]]
    """
    pts = np.asarray(points_cam, dtype=float).reshape(-1, 3)
    if dist is not None and np.any(np.asarray(dist) != 0):
        uv, _ = cv2.projectPoints(pts, np.zeros(3), np.zeros(3), np.asarray(K, dtype=float),
                                  np.asarray(dist, dtype=float))
        return np.asarray(uv.reshape(-1, 2), dtype=float)
    uvw = pts @ np.asarray(K, dtype=float).T
    return np.asarray(uvw[:, :2] / uvw[:, 2:3])


def backproject(K: Array, uv: ArrayLike, depth: ArrayLike) -> Array:
    """(N, 2) pixels and (N,) depths along z → (N, 3) camera points (no distortion: rectified pixels).

    >>> backproject(np.array([[100.0, 0, 50], [0, 100.0, 40], [0, 0, 1]]), [[60.0, 35.0]], [2.0]).tolist()
    [[0.2, -0.1, 2.0]]
    """
    uv = np.asarray(uv, dtype=float).reshape(-1, 2)
    z = np.asarray(depth, dtype=float).reshape(-1)
    K = np.asarray(K, dtype=float)
    x = (uv[:, 0] - K[0, 2] - K[0, 1] * (uv[:, 1] - K[1, 2]) / K[1, 1]) / K[0, 0]
    y = (uv[:, 1] - K[1, 2]) / K[1, 1]
    return np.column_stack([x * z, y * z, z])


@dataclass(frozen=True)
class RectifiedStereo:
    """A rectified pair's geometry: shared focal length and rows, baseline, horizontal principal-point offset."""

    fx: float
    fy: float
    cx: float
    cy: float
    baseline: float
    """Metres between the optical centres, the right camera at +baseline along x."""
    image_size: tuple[int, int]
    """(width, height) in pixels."""
    doffs: float = 0.0
    """cx_right − cx_left in pixels (0 after `cv2.stereoRectify` with CALIB_ZERO_DISPARITY)."""

    @staticmethod
    def from_K(K: ArrayLike, baseline: float, image_size: tuple[int, int], doffs: float = 0.0) -> RectifiedStereo:
        """From the left camera's K (both cameras share it, up to `doffs`)."""
        K = np.asarray(K, dtype=float)
        return RectifiedStereo(float(K[0, 0]), float(K[1, 1]), float(K[0, 2]), float(K[1, 2]), float(baseline),
                               (int(image_size[0]), int(image_size[1])), float(doffs))

    @staticmethod
    def from_projections(P_left: ArrayLike, P_right: ArrayLike, image_size: tuple[int, int]) -> RectifiedStereo:
        """From rectified 3×4 projection matrices (KITTI's P0/P1, or stereoRectify's P1/P2).

        >>> P0 = np.array([[700.0, 0, 600, 0], [0, 700, 180, 0], [0, 0, 1, 0]])
        >>> P1 = P0.copy(); P1[0, 3] = -700 * 0.5
        >>> RectifiedStereo.from_projections(P0, P1, (1200, 370)).baseline
        0.5
        """
        Pl, Pr = np.asarray(P_left, dtype=float), np.asarray(P_right, dtype=float)
        baseline = (Pl[0, 3] - Pr[0, 3]) / Pr[0, 0]
        return RectifiedStereo(float(Pl[0, 0]), float(Pl[1, 1]), float(Pl[0, 2]), float(Pl[1, 2]), float(baseline),
                               (int(image_size[0]), int(image_size[1])), float(Pr[0, 2] - Pl[0, 2]))

    @property
    def K(self) -> Array:
        """The left camera's 3×3 intrinsics."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    @property
    def fB(self) -> float:
        """Focal length times baseline (pixel·metres): Z = fB / (d + doffs)."""
        return self.fx * self.baseline

    def depth(self, disparity: ArrayLike) -> Array:
        """Depth along z (m) for image disparities d = u_l − u_r."""
        return np.asarray(self.fB / (np.asarray(disparity, dtype=float) + self.doffs))

    def disparity(self, depth: ArrayLike) -> Array:
        """Image disparity for depths along z."""
        return np.asarray(self.fB / np.asarray(depth, dtype=float) - self.doffs)

    def disparity_range(self, min_range: float = 0.3, max_range: float | None = None) -> tuple[float, float]:
        """(d_min, d_max) for depths in [min_range, max_range]; d_min ≥ 0 (positive disparities only) and
        d_max ≤ the image width."""
        d_min = 0.0 if max_range is None else max(0.0, float(self.disparity(max_range)))
        d_max = min(float(self.image_size[0]), float(self.disparity(min_range)))
        return d_min, d_max


@dataclass(frozen=True, eq=False)
class Rectification:
    """Remap tables and the rectified geometry of a calibrated pair (from `StereoCalibration.rectification`)."""

    geometry: RectifiedStereo
    R_left: Array
    """Rotation from the original left camera to the rectified left camera (OpenCV's R1)."""
    R_right: Array
    """Rotation from the original right camera to the rectified right camera (OpenCV's R2)."""
    maps_left: tuple[RemapTable, RemapTable]
    """`cv2.initUndistortRectifyMap` tables (CV_16SC2 and its interpolation table) for the left image."""
    maps_right: tuple[RemapTable, RemapTable]
    P_left: Array
    P_right: Array
    Q: Array

    def apply(self, left: NDArray[np.uint8], right: NDArray[np.uint8]) -> tuple[NDArray[np.uint8],
                                                                                  NDArray[np.uint8]]:
        """Rectify a raw pair (bilinear remap)."""
        rect_l = cv2.remap(left, self.maps_left[0], self.maps_left[1], cv2.INTER_LINEAR)
        rect_r = cv2.remap(right, self.maps_right[0], self.maps_right[1], cv2.INTER_LINEAR)
        return np.asarray(rect_l, dtype=np.uint8), np.asarray(rect_r, dtype=np.uint8)


@dataclass(frozen=True, eq=False)
class StereoCalibration:
    """A calibrated stereo pair: intrinsics, distortion, and the left → right rigid motion (X_r = R·X_l + T)."""

    K_left: Array
    K_right: Array
    dist: Array = field(default_factory=lambda: np.zeros(5))
    """Distortion coefficients (OpenCV order) of both cameras, unless `dist_right` is given."""
    R: Array = field(default_factory=lambda: np.eye(3))
    T: Array = field(default_factory=lambda: np.zeros(3))
    image_size: tuple[int, int] = (0, 0)
    """(width, height) in pixels."""
    dist_right: Array | None = None

    @staticmethod
    def ideal(K: ArrayLike, baseline: float, image_size: tuple[int, int]) -> StereoCalibration:
        """An already rectified pair (same K, no distortion, right camera at +baseline along x)."""
        K = np.asarray(K, dtype=float)
        return StereoCalibration(K, K.copy(), np.zeros(5), np.eye(3), np.array([-float(baseline), 0.0, 0.0]),
                                 (int(image_size[0]), int(image_size[1])))

    @property
    def baseline(self) -> float:
        return float(np.linalg.norm(self.T))

    def is_rectified(self, tol: float = 1e-9) -> bool:
        """True when the pair needs no remapping: no distortion, R = I, T along −x, equal focal lengths and rows."""
        dist_r = self.dist if self.dist_right is None else self.dist_right
        Kl, Kr = np.asarray(self.K_left, dtype=float), np.asarray(self.K_right, dtype=float)
        T = np.asarray(self.T, dtype=float).reshape(3)
        return bool(not np.any(np.abs(self.dist) > tol) and not np.any(np.abs(dist_r) > tol)
                    and np.allclose(self.R, np.eye(3), atol=tol) and T[0] < 0
                    and abs(T[1]) <= tol * abs(T[0]) + tol and abs(T[2]) <= tol * abs(T[0]) + tol
                    and np.allclose(Kl[[0, 1, 1, 0], [0, 1, 2, 1]], Kr[[0, 1, 1, 0], [0, 1, 2, 1]], atol=tol))

    def rectified_geometry(self) -> RectifiedStereo:
        """The geometry of an already rectified pair (see `is_rectified`), or of its rectification."""
        if self.is_rectified():
            return RectifiedStereo.from_K(self.K_left, self.baseline, self.image_size,
                                          float(self.K_right[0, 2] - self.K_left[0, 2]))
        return self.rectification.geometry

    @cached_property
    def rectification(self) -> Rectification:
        """`cv2.stereoRectify` (zero disparity at infinity, no black borders cropped: alpha = 0) and the remap
        tables of `cv2.initUndistortRectifyMap`, computed once."""
        size = (int(self.image_size[0]), int(self.image_size[1]))
        if size[0] <= 0 or size[1] <= 0:
            raise ValueError("StereoCalibration.image_size must be set to rectify")
        dist_r = self.dist if self.dist_right is None else self.dist_right
        Kl, Kr = np.asarray(self.K_left, dtype=float), np.asarray(self.K_right, dtype=float)
        dl, dr = np.asarray(self.dist, dtype=float), np.asarray(dist_r, dtype=float)
        R1, R2, P1, P2, Q, _, _ = cv2.stereoRectify(Kl, dl, Kr, dr, size, np.asarray(self.R, dtype=float),
                                                    np.asarray(self.T, dtype=float).reshape(3, 1),
                                                    flags=cv2.CALIB_ZERO_DISPARITY, alpha=0.0)
        maps_l = cv2.initUndistortRectifyMap(Kl, dl, R1, P1, size, cv2.CV_16SC2)
        maps_r = cv2.initUndistortRectifyMap(Kr, dr, R2, P2, size, cv2.CV_16SC2)
        geometry = RectifiedStereo.from_projections(P1, P2, size)
        return Rectification(geometry, np.asarray(R1), np.asarray(R2), (maps_l[0], maps_l[1]),
                             (maps_r[0], maps_r[1]),
                             np.asarray(P1), np.asarray(P2), np.asarray(Q))


__all__ = ["Rectification", "RectifiedStereo", "StereoCalibration", "backproject", "project"]
