"""The 6-DOF motion between two positions from points triangulated at the first and seen at the second.

PnP-RANSAC (`cv2.solvePnPRansac`, seeded with the predicted motion when there is one) finds the inliers and a first
estimate; Levenberg–Marquardt (`cv2.solvePnPRefineLM`) refines it on the left image; when the points are seen in
the second position's right image too, a robust least-squares pass (Huber, 1 px) minimises the reprojection error
in both images of the second pair (the four-image circle of seed 003's classic scheme, Fig. 2), which ties the
scale to both stereo pairs rather than to the first one alone.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from mission.geometry import invert
from perception_plugins.vo.se3 import from_rotvec_translation, to_rotvec

Array = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class Motion:
    """T_a_b (position b in position a's camera frame) and the indices of the points that support it."""

    T_a_b: Array
    inliers: NDArray[np.int_]
    rms_px: float
    disparity_offset: float = 0.0
    """The correction to the pair's disparity offset estimated with the motion (0 unless asked for)."""

    @property
    def count(self) -> int:
        return int(len(self.inliers))


def _project(rvec: Array, tvec: Array, points: Array, K: Array, shift: float = 0.0) -> Array:
    """Pixels of `points` (frame a) in a camera at T_b_a = (rvec, tvec), optionally displaced along its x."""
    R = cv2.Rodrigues(rvec)[0]
    p = points @ R.T + tvec
    p[:, 0] -= shift
    z = np.maximum(p[:, 2], 1e-6)
    return np.column_stack([K[0, 0] * p[:, 0] / z + K[0, 2], K[1, 1] * p[:, 1] / z + K[1, 2]])


def robust_gauss_newton(residuals: Callable[[Array], Array], x0: Array, huber: float = 1.0,
                        iterations: int = 10, step: float = 1e-6) -> Array:
    """Minimise Σ huber(r_i(x)) by iteratively reweighted Gauss–Newton with a forward-difference Jacobian (a few
    parameters, hundreds of residuals: 7×7 normal equations, no large factorisation)."""
    x = np.asarray(x0, dtype=float).copy()
    for _ in range(iterations):
        r = residuals(x)
        J = np.empty((len(r), len(x)))
        for k in range(len(x)):
            dx = np.zeros_like(x)
            dx[k] = step
            J[:, k] = (residuals(x + dx) - r) / step
        a = np.abs(r)
        w = np.where(a <= huber, 1.0, huber / np.maximum(a, 1e-12))
        H = J.T @ (w[:, None] * J) + 1e-9 * np.eye(len(x))
        delta = -np.linalg.solve(H, J.T @ (w * r))
        x += delta
        if np.max(np.abs(delta)) < 1e-9:
            break
    return x


def estimate_motion(points_a: Array, uv_b: Array, K: Array, *, uv_b_right: Array | None = None,
                    right_ok: NDArray[np.bool_] | None = None, baseline: float = 0.0,
                    T_a_b_guess: Array | None = None, threshold_px: float = 1.5, min_inliers: int = 6,
                    iterations: int = 200, doffs: float = 0.0, estimate_offset: bool = False) -> Motion | None:
    """T_a_b from points triangulated in camera a and their pixels in camera b's left (and right) image, or None
    when RANSAC cannot find `min_inliers` consistent points."""
    n = len(points_a)
    if n < max(min_inliers, 4):
        return None
    obj = np.ascontiguousarray(points_a, dtype=np.float64)
    img = np.ascontiguousarray(uv_b, dtype=np.float64)
    use_guess = T_a_b_guess is not None
    rvec0 = tvec0 = None
    if T_a_b_guess is not None:
        T_b_a = invert(T_a_b_guess)
        rvec0, tvec0 = to_rotvec(T_b_a[:3, :3]).reshape(3, 1), T_b_a[:3, 3].reshape(3, 1).copy()
    ok, rvec, tvec, inl = cv2.solvePnPRansac(obj, img, K, None, rvec0, tvec0, useExtrinsicGuess=use_guess,
                                             iterationsCount=iterations, reprojectionError=threshold_px,
                                             confidence=0.999, flags=cv2.SOLVEPNP_ITERATIVE if use_guess
                                             else cv2.SOLVEPNP_EPNP)
    if not ok or inl is None or len(inl) < min_inliers:
        return None
    inliers = inl.reshape(-1)
    rvec, tvec = cv2.solvePnPRefineLM(obj[inliers], img[inliers], K, None, rvec, tvec)
    # Re-select inliers against the refined motion: RANSAC's minimal-set model is rougher than the threshold.
    rv, tv = np.asarray(rvec, dtype=np.float64).reshape(3), np.asarray(tvec, dtype=np.float64).reshape(3)
    err = np.linalg.norm(_project(rv, tv, obj, K) - img, axis=1)
    inliers = np.flatnonzero(err <= threshold_px)
    if len(inliers) < min_inliers:
        return None
    rvec, tvec = cv2.solvePnPRefineLM(obj[inliers], img[inliers], K, None, rvec, tvec)
    x = np.concatenate([rvec.reshape(3), tvec.reshape(3)])
    offset = 0.0
    if uv_b_right is not None and baseline > 0:
        has_right = np.ones(n, dtype=bool) if right_ok is None else np.asarray(right_ok, dtype=bool)
        both = inliers[has_right[inliers]]
        if len(both) >= min_inliers:
            fB = K[0, 0] * baseline
            P, L, Rr = obj[inliers], img[inliers], np.asarray(uv_b_right, dtype=float)[both]
            D = fB / np.maximum(obj[:, 2], 1e-6)  # the first pair's disparities (with its offset)
            pick = np.searchsorted(inliers, both)

            def residuals(v: Array) -> Array:
                Pv = P if not estimate_offset else P * (D[inliers] / (D[inliers] + v[6]))[:, None]
                left = _project(v[:3], v[3:6], Pv, K)
                right = _project(v[:3], v[3:6], Pv[pick], K, baseline)
                right[:, 0] += doffs + (v[6] if estimate_offset else 0.0)
                return np.concatenate([(left - L).ravel(), (right - Rr).ravel()])

            x0 = np.concatenate([x, [0.0]]) if estimate_offset else x
            sol = robust_gauss_newton(residuals, x0)
            x = np.asarray(sol[:6], dtype=np.float64)
            offset = float(sol[6]) if estimate_offset else 0.0
            if estimate_offset:
                obj = obj * (D / (D + offset))[:, None]
    err = np.linalg.norm(_project(x[:3], x[3:], obj[inliers], K) - img[inliers], axis=1)
    T_b_a = from_rotvec_translation(x[:3], x[3:])
    return Motion(invert(T_b_a), inliers, float(np.sqrt(np.mean(err**2))), offset)


__all__ = ["Motion", "estimate_motion"]
