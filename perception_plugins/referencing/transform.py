"""The least-squares rigid transform between identified point sets (seed 002 §3.3): min Σ‖P_k − H·C_k‖.

`rigid_transform` is Kabsch's solution (Umeyama without scale): the rotation is always proper (det = +1), so a
mirror image of a set never fits better than its own residual says. `robust_rigid_transform` refines it against
wrong pairs by iteratively reweighted least squares (Cauchy weights) followed by residual-based rejection.

>>> import numpy as np
>>> src = np.array([[0.0, 0, 0], [1, 0, 0], [0, 2, 0], [0, 0, 3]])
>>> T = np.eye(4); T[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]; T[:3, 3] = [5, 6, 7]
>>> dst = src @ T[:3, :3].T + T[:3, 3]
>>> bool(np.allclose(rigid_transform(src, dst), T))
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mission.geometry import _as_points, rigid_transform
from mission.geometry import rotation_angle_deg as rotation_angle_deg
from mission.geometry import transform_points as apply

Array = NDArray[np.float64]


def is_degenerate(points: Array, min_spread: float) -> bool:
    """True when the points are (nearly) collinear: their second principal spread is below `min_spread` (m)."""
    pts = _as_points(points, "points")
    if len(pts) < 3:
        return True
    s = np.linalg.svd(pts - pts.mean(axis=0), compute_uv=False)
    return bool(s[1] / math.sqrt(len(pts)) < min_spread)


def triangle_transforms(model_tri: Array, cloud_tris: Array) -> tuple[Array, Array]:
    """Proper transforms (R (h,3,3), t (h,3)) taking one model triangle (3,3) onto each cloud triangle (h,3,3).

    A frame is built on each triangle (origin at the centroid, x along the first edge, z along the normal), so
    that R = F_cloud·F_modelᵀ: exact for congruent triangles, never a reflection, and vectorised for the
    thousands of hypotheses of an anchor triangle.
    """
    def frames(tri: Array) -> Array:
        e1 = tri[..., 1, :] - tri[..., 0, :]
        e2 = tri[..., 2, :] - tri[..., 0, :]
        x = e1 / np.sqrt(np.einsum("...i,...i->...", e1, e1))[..., None]
        z = np.stack([x[..., 1] * e2[..., 2] - x[..., 2] * e2[..., 1],
                      x[..., 2] * e2[..., 0] - x[..., 0] * e2[..., 2],
                      x[..., 0] * e2[..., 1] - x[..., 1] * e2[..., 0]], axis=-1)
        z = z / np.maximum(np.sqrt(np.einsum("...i,...i->...", z, z)), 1e-12)[..., None]
        y = np.stack([z[..., 1] * x[..., 2] - z[..., 2] * x[..., 1],
                      z[..., 2] * x[..., 0] - z[..., 0] * x[..., 2],
                      z[..., 0] * x[..., 1] - z[..., 1] * x[..., 0]], axis=-1)
        return np.stack([x, y, z], axis=-1)

    model_tri = np.asarray(model_tri, dtype=float)
    cloud_tris = np.asarray(cloud_tris, dtype=float)
    fm = frames(model_tri)
    fc = frames(cloud_tris)
    # R = F_cloud·F_modelᵀ and t = centre_cloud − R·centre_model, written out: BLAS is slow on these shapes
    rot = fc[:, :, None, 0] * fm[:, 0] + fc[:, :, None, 1] * fm[:, 1] + fc[:, :, None, 2] * fm[:, 2]
    centre = (cloud_tris[:, 0] + cloud_tris[:, 1] + cloud_tris[:, 2]) / 3.0
    mc = model_tri.mean(axis=0)
    t = centre - (rot[:, :, 0] * mc[0] + rot[:, :, 1] * mc[1] + rot[:, :, 2] * mc[2])
    return rot, t


def rigid_transforms(src: Array, dst: Array, weights: Array | None = None) -> tuple[Array, Array]:
    """Batched Kabsch: proper (R (h,3,3), t (h,3)) with dst[h] ≈ R[h]·src[h] + t[h] for (h, n, 3) arrays,
    optionally weighted (h, n) (a zero weight leaves a pair out)."""
    src, dst = np.asarray(src, dtype=float), np.asarray(dst, dtype=float)
    if weights is None:
        weights = np.ones(src.shape[:2])
    w = np.asarray(weights, dtype=float)
    w = w / np.maximum(w.sum(axis=1, keepdims=True), 1e-300)
    mu_s, mu_d = np.einsum("hn,hni->hi", w, src), np.einsum("hn,hni->hi", w, dst)
    cov = np.einsum("hni,hnj->hij", (dst - mu_d[:, None]) * w[:, :, None], src - mu_s[:, None])
    u, _, vt = np.linalg.svd(cov)
    d = np.sign(np.linalg.det(u @ vt))
    d[d == 0] = 1.0
    u[:, :, 2] *= d[:, None]
    rot = u @ vt
    return rot, mu_d - np.einsum("hij,hj->hi", rot, mu_s)


def msac_score(residuals: Array, threshold: float) -> float:
    """Σ max(0, 1 − (r / threshold)²): each pair counts for how well it fits (MSAC, Torr & Zisserman 2000), so
    that a set fitting at the noise level beats a slightly larger one that only fits near the threshold.

    >>> msac_score(np.array([0.0, 0.05, 0.2]), 0.1)
    1.75
    """
    r = np.asarray(residuals, dtype=float) / threshold
    return float(np.sum(np.clip(1.0 - r * r, 0.0, None)))


@dataclass(frozen=True)
class RobustFit:
    """A robust fit: the transform, which pairs it keeps, every pair's residual (m) and the kept pairs' RMS."""

    T: Array
    inliers: NDArray[np.bool_]
    residuals: Array
    rms: float


def robust_rigid_transform(src: Array, dst: Array, threshold: float, iterations: int = 10,
                           max_rejected: float = 1.0) -> RobustFit:
    """Kabsch refined by Cauchy-weighted least squares (scale threshold / 2, so that a wrong pair a few
    thresholds off barely pulls), then pairs with residual > `threshold` rejected and the rest fitted by
    plain least squares (the efficient estimate once the wrong pairs are out).

    At most `max_rejected` (a fraction) of the pairs may be rejected, the worst first; the result says which
    pairs remain (at least three) and their RMS residual, so callers accept or refuse the fit.
    """
    src, dst = _as_points(src, "src"), _as_points(dst, "dst")
    T = rigid_transform(src, dst)
    scale = max(threshold / 2.0, 1e-9)
    for _ in range(iterations):
        r = np.linalg.norm(apply(T, src) - dst, axis=1)
        w = 1.0 / (1.0 + (r / scale) ** 2)
        T_new = rigid_transform(src, dst, w)
        converged = float(np.abs(T_new - T).max()) < 1e-9
        T = T_new
        if converged:
            break
    r = np.linalg.norm(apply(T, src) - dst, axis=1)
    keep = r <= threshold
    min_kept = min(len(src), max(3, math.ceil((1.0 - max_rejected) * len(src))))
    if keep.sum() < min_kept:                          # too many would go: keep the best, the caller judges
        keep = np.zeros(len(src), dtype=bool)
        keep[np.argsort(r)[:min_kept]] = True
    if keep.sum() >= 3:                                 # the least-squares fit of the kept pairs (seed §3.3)
        T = rigid_transform(src[keep], dst[keep])
        r = np.linalg.norm(apply(T, src) - dst, axis=1)
    rms = float(np.sqrt(np.mean(r[keep] ** 2))) if keep.any() else math.inf
    return RobustFit(T=T, inliers=keep, residuals=r, rms=rms)


__all__ = ["RobustFit", "apply", "is_degenerate", "msac_score", "rigid_transform", "rigid_transforms",
           "robust_rigid_transform", "rotation_angle_deg", "triangle_transforms"]
