"""Rigid-body geometry that the whole project shares: 4×4 homogeneous transforms `T_a_b` (frame b → frame a),
their inverse, applying them to points, and the least-squares rigid transform between matched point sets (Kabsch's
solution, Umeyama without scale; seed 002 §3.3).

Part of the plug-in API: it imports numpy only, so plug-ins may use it without loading the executive.

>>> src = np.array([[0.0, 0, 0], [1, 0, 0], [0, 2, 0], [0, 0, 3]])
>>> T = np.eye(4); T[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]; T[:3, 3] = [5, 6, 7]
>>> dst = transform_points(T, src)
>>> bool(np.allclose(rigid_transform(src, dst), T)), bool(np.allclose(invert(T) @ T, np.eye(4)))
(True, True)
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


def invert(T_a_b: Array) -> Array:
    """T_b_a of a rigid T_a_b, or of each of a stack (..., 4, 4) of them.

    >>> T = np.eye(4); T[:3, 3] = [1.0, 2.0, 3.0]
    >>> (invert(np.stack([T, np.eye(4)]))[:, :3, 3] + 0.0).tolist()
    [[-1.0, -2.0, -3.0], [0.0, 0.0, 0.0]]
    """
    T_a_b = np.asarray(T_a_b, dtype=float)
    if T_a_b.ndim == 2:
        T = np.eye(4)
        R = T_a_b[:3, :3]
        T[:3, :3] = R.T
        T[:3, 3] = -R.T @ T_a_b[:3, 3]
        return T
    R_b_a = np.swapaxes(T_a_b[..., :3, :3], -1, -2)
    T = np.zeros_like(T_a_b)
    T[..., :3, :3] = R_b_a
    T[..., :3, 3] = -np.einsum("...ij,...j->...i", R_b_a, T_a_b[..., :3, 3])
    T[..., 3, 3] = 1.0
    return T


def transform_points(T_a_b: Array, points_b: Array) -> Array:
    """Map (N, 3) points from frame b to frame a."""
    pts = np.asarray(points_b, dtype=float).reshape(-1, 3)
    return np.asarray(pts @ T_a_b[:3, :3].T + T_a_b[:3, 3])


def rotation_angle_deg(R: Array) -> float:
    """The angle of a rotation matrix (or of a transform's rotation), in degrees (0…180)."""
    c = (float(np.trace(R[:3, :3])) - 1.0) / 2.0
    return math.degrees(math.acos(min(1.0, max(-1.0, c))))


def rigid_transform(src: Array, dst: Array, weights: Array | None = None) -> Array:
    """The 4×4 proper rigid transform T minimising Σ w‖dst − T·src‖² (rotation det = +1, no scale).

    Needs at least three pairs; for collinear sets the rotation about their line is arbitrary but proper.
    """
    src, dst = _as_points(src, "src"), _as_points(dst, "dst")
    if src.shape != dst.shape or len(src) < 3:
        raise ValueError(f"src and dst must be matching (n >= 3, 3) arrays, got {src.shape} and {dst.shape}")
    if weights is None:
        mu_s, mu_d = src.mean(axis=0), dst.mean(axis=0)
        cov = (dst - mu_d).T @ (src - mu_s)
    else:
        w = np.asarray(weights, dtype=float) / np.sum(weights)
        mu_s, mu_d = w @ src, w @ dst
        cov = (dst - mu_d).T @ ((src - mu_s) * w[:, None])
    u, _, vt = np.linalg.svd(cov)
    rot = u @ vt
    if _det3(rot) < 0:  # flip the weakest axis rather than reflect
        u[:, 2] = -u[:, 2]
        rot = u @ vt
    T = np.eye(4)
    T[:3, :3] = rot
    T[:3, 3] = mu_d - rot @ mu_s
    return T


def _as_points(points: Array, name: str) -> Array:
    arr = np.asarray(points, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"{name} must have shape (n, 3), got {arr.shape}")
    return arr


def _det3(m: Array) -> float:
    return float(m[0, 0] * (m[1, 1] * m[2, 2] - m[1, 2] * m[2, 1]) - m[0, 1] * (m[1, 0] * m[2, 2] - m[1, 2] * m[2, 0])
                 + m[0, 2] * (m[1, 0] * m[2, 1] - m[1, 1] * m[2, 0]))
