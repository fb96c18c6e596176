"""Pose refinement of a range map against the surface fused so far (seed 003 "3D reconstruction": the views are
brought into one frame by the navigation's poses; this refines each by point-to-plane ICP, Chen and Medioni).

The model is the points (with normals) of the range maps already placed; each new map's points, placed at the
pose prior, are matched to their nearest model points within `max_distance`, and the pose is corrected by the
linearised point-to-plane least squares, a few times over.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from perception_plugins.reconstruction.depth import RangeMap

Array = NDArray[np.float64]


def points_and_normals(rmap: RangeMap, stride: int = 6) -> tuple[Array, Array]:
    """(N, 3) camera points of every `stride`-th valid pixel and their unit normals (facing the camera), from the
    depth map's central differences."""
    K = rmap.K
    z = rmap.depth.astype(float)
    h, w = z.shape
    x = ((np.arange(w) - K[0, 2]) / K[0, 0])[None, :]
    y = ((np.arange(h) - K[1, 2]) / K[1, 1])[:, None]
    P = np.stack([x * z, y * z, z], axis=-1)
    du = np.full_like(P, np.nan)
    dv = np.full_like(P, np.nan)
    du[:, 1:-1] = P[:, 2:] - P[:, :-2]
    dv[1:-1] = P[2:] - P[:-2]
    n = np.cross(du, dv)[::stride, ::stride].reshape(-1, 3)
    p = P[::stride, ::stride].reshape(-1, 3)
    norm = np.linalg.norm(n, axis=1)
    ok = np.isfinite(norm) & (norm > 0) & np.all(np.isfinite(p), axis=1)
    n = n[ok] / norm[ok, None]
    p = p[ok]
    n *= -np.sign(np.sum(n * p, axis=1))[:, None]  # towards the camera
    return p, n


def _rotation(omega: Array) -> Array:
    angle = float(np.linalg.norm(omega))
    if angle < 1e-12:
        return np.eye(3)
    k = omega / angle
    Kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.asarray(np.eye(3) + np.sin(angle) * Kx + (1.0 - np.cos(angle)) * Kx @ Kx)


def refine_pose(points_cam: Array, T_prior: Array, model_points: Array, model_normals: Array,
                tree: cKDTree | None = None, iterations: int = 10, max_distance: float = 0.1,
                min_matches: int = 200) -> tuple[Array, int]:
    """T_world_cam that best lays `points_cam` on the model's surface, starting from `T_prior`, and the number of
    matches of the last iteration (the prior itself when fewer than `min_matches` points match)."""
    tree = tree or cKDTree(model_points)
    T = np.asarray(T_prior, dtype=float).copy()
    matched = 0
    for _ in range(iterations):
        p = points_cam @ T[:3, :3].T + T[:3, 3]
        dist, idx = tree.query(p, distance_upper_bound=max_distance)
        ok = np.isfinite(dist)
        matched = int(ok.sum())
        if matched < min_matches:
            return np.asarray(T_prior, dtype=float).copy(), matched
        q, n, p = model_points[idx[ok]], model_normals[idx[ok]], p[ok]
        r = np.sum(n * (p - q), axis=1)
        A = np.hstack([np.cross(p, n), n])
        delta = np.linalg.lstsq(A, -r, rcond=None)[0]
        step = np.eye(4)
        step[:3, :3] = _rotation(delta[:3])
        step[:3, 3] = delta[3:]
        T = step @ T
        if np.linalg.norm(delta) < 1e-5:
            break
    return T, matched


def refine_poses(range_maps: list[RangeMap], poses: list[Array], stride: int = 6) -> list[Array]:
    """Each map's pose refined in turn against the points of the maps before it, placed at their refined poses
    (frame to model; the first map keeps its pose, so the result is as far from the world frame as it is)."""
    refined: list[Array] = []
    model_points: list[Array] = []
    model_normals: list[Array] = []
    for rmap, T_prior in zip(range_maps, poses, strict=True):
        p, n = points_and_normals(rmap, stride)
        T = np.asarray(T_prior, dtype=float)
        if model_points:
            T, _ = refine_pose(p, T, np.vstack(model_points), np.vstack(model_normals))
        refined.append(T)
        model_points.append(p @ T[:3, :3].T + T[:3, 3])
        model_normals.append(n @ T[:3, :3].T)
    return refined


__all__ = ["points_and_normals", "refine_pose", "refine_poses"]
