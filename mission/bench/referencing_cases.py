"""Seeded identification and referencing cases with their ground truth, for the referencing benchmark.

A case: an object of about 8 m (a skid 7–9 × 4–6 m with a module and a smaller box on top), a model of N
characteristic points on its visible surfaces (a third at box corners, the rest on faces), a down-looking
camera 3–4 m above the module at a random heading and a few degrees of tilt. 60–100 % of the model points are
in the cloud (at least 5); the rest of the cloud (≥ 90 % of M) are outliers on the seabed around the object (with
5 cm relief) and on the object's own faces, never within 0.2 m (10σ) of a model point's true position: a point
that close is the characteristic point itself as a feature detector reports it. Every cloud point gets
σ = 2 cm of noise per axis. Tolerance 0.1 m (5σ; a distance difference has σ√2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mission.geometry import invert, rigid_transform, rotation_angle_deg

Array = NDArray[np.float64]

SIGMA = 0.02
TOLERANCE = 3 * math.sqrt(2) * SIGMA            # 3σ of a distance difference (each end has σ per axis)
EXCLUSION = 0.2


@dataclass(frozen=True)
class Case:
    """One seeded identification problem with its ground truth."""

    model: Array                     # (N, 3) object frame
    cloud: Array                     # (M, 3) camera frame
    truth: dict[int, int]            # model index → cloud index, for the visible model points
    T_cloud_model: Array             # true transform, object → camera
    boxes: list[tuple[Array, Array]]  # (lo, hi) corners of the object's boxes, object frame (z down)
    seabed_z: float


def _boxes(rng: np.random.Generator) -> list[tuple[Array, Array]]:
    length, width, skid_h = rng.uniform(7, 9), rng.uniform(4, 6), rng.uniform(0.4, 0.8)
    boxes = [(np.array([0.0, 0.0, 0.0]), np.array([length, width, skid_h]))]
    for size_l, size_w, size_h in [((2.5, 4.5), (2.0, 3.5), (1.0, 2.5)), ((0.8, 2.0), (0.8, 2.0), (0.3, 1.0))]:
        dims = np.minimum([rng.uniform(*size_l), rng.uniform(*size_w)], [length - 0.6, width - 0.6])
        lo_xy = np.array([rng.uniform(0.3, length - dims[0] - 0.3), rng.uniform(0.3, width - dims[1] - 0.3)])
        height = rng.uniform(*size_h)
        lo = np.array([lo_xy[0], lo_xy[1], -height])
        hi = np.array([lo_xy[0] + dims[0], lo_xy[1] + dims[1], 0.0])
        if len(boxes) == 2:                                   # the small box must not sit inside the module
            m_lo, m_hi = boxes[1]
            if np.all(lo[:2] < m_hi[:2]) and np.all(hi[:2] > m_lo[:2]):
                lo[2], hi[2] = m_lo[2] - height, m_lo[2]      # then it stands on the module's top
                lo[:2] = m_lo[:2] + 0.2
                hi[:2] = np.minimum(lo[:2] + dims, m_hi[:2] - 0.2)
        boxes.append((lo, hi))
    return boxes


def _inside_any(points: Array, boxes: list[tuple[Array, Array]], shrink: float = 1e-3) -> NDArray[np.bool_]:
    out = np.zeros(len(points), dtype=bool)
    for lo, hi in boxes:
        out |= np.all((points > lo + shrink) & (points < hi - shrink), axis=1)
    return out


def _surface_points(rng: np.random.Generator, boxes: list[tuple[Array, Array]], count: int) -> Array:
    """Points uniform on the boxes' tops and side faces (seen from above), not inside another box."""
    faces = []                                               # (origin, edge u, edge v)
    for lo, hi in boxes:
        d = hi - lo
        faces.append((lo.copy(), np.array([d[0], 0, 0]), np.array([0, d[1], 0])))        # top (z = lo z)
        for axis in (0, 1):
            for side in (lo, hi):
                o = lo.copy()
                o[axis] = side[axis]
                u = np.zeros(3)
                u[1 - axis] = d[1 - axis]
                faces.append((o, u, np.array([0, 0, d[2]])))
    areas = np.array([np.linalg.norm(np.cross(u, v)) for _, u, v in faces])
    out: list[Array] = []
    while sum(len(o) for o in out) < count:
        f = rng.choice(len(faces), size=2 * count, p=areas / areas.sum())
        ab = rng.random((2 * count, 2))
        o = np.array([faces[i][0] for i in f])
        u = np.array([faces[i][1] for i in f])
        v = np.array([faces[i][2] for i in f])
        pts = o + ab[:, :1] * u + ab[:, 1:] * v
        out.append(pts[~_inside_any(pts, boxes)])
    return np.concatenate(out)[:count]


def _model(rng: np.random.Generator, boxes: list[tuple[Array, Array]], n: int) -> Array:
    corners = []
    for lo, hi in boxes:
        for x in (lo[0], hi[0]):
            for y in (lo[1], hi[1]):
                corners.append([x, y, lo[2]])
    corners_arr = np.array(corners)
    corners_arr = corners_arr[~_inside_any(corners_arr, boxes)]
    pool = np.vstack([corners_arr[rng.permutation(len(corners_arr))][: max(1, n // 3)],
                      _surface_points(rng, boxes, 20 * n)])
    chosen: list[Array] = []
    for p in pool:                                          # characteristic points at least 0.4 m apart
        if all(np.linalg.norm(p - q) >= 0.4 for q in chosen):
            chosen.append(p)
            if len(chosen) == n:
                break
    return np.array(chosen)


def random_case(seed: int, n_model: int, n_cloud: int, sigma: float = SIGMA) -> Case:
    """A seeded case (see the module docstring)."""
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(seed)
    boxes = _boxes(rng)
    model = _model(rng, boxes, n_model)
    visible = max(5, int(round(rng.uniform(0.6, 1.0) * n_model)))
    visible_idx = rng.permutation(n_model)[:visible]
    seabed_z = float(boxes[0][1][2])
    length, width = boxes[0][1][0], boxes[0][1][1]
    n_out = n_cloud - visible
    outliers: list[Array] = []
    while sum(len(o) for o in outliers) < n_out:
        k = n_out
        seabed = np.column_stack([rng.uniform(-3, length + 3, k), rng.uniform(-3, width + 3, k),
                                  seabed_z + rng.normal(0, 0.05, k)])
        seabed = seabed[~((seabed[:, 0] > 0) & (seabed[:, 0] < length) & (seabed[:, 1] > 0) & (seabed[:, 1] < width))]
        pts = np.vstack([seabed[: k // 2], _surface_points(rng, boxes, k - k // 2)])
        far = np.min(np.linalg.norm(pts[:, None, :] - model[None, :, :], axis=2), axis=1) >= EXCLUSION
        outliers.append(pts[far])
    points_obj = np.vstack([model[visible_idx], np.concatenate(outliers)[:n_out]])
    heading = rng.uniform(0, 360)
    tilt = rng.normal(0, 3, 2)
    R_obj_cam = Rotation.from_euler("zxy", [heading, tilt[0], tilt[1]], degrees=True).as_matrix()
    top = min(lo[2] for lo, _ in boxes)
    cam = np.array([length / 2 + rng.uniform(-1, 1), width / 2 + rng.uniform(-1, 1), top - rng.uniform(3, 4)])
    T_cloud_model = np.eye(4)
    T_cloud_model[:3, :3] = R_obj_cam.T
    T_cloud_model[:3, 3] = -R_obj_cam.T @ cam
    cloud = points_obj @ T_cloud_model[:3, :3].T + T_cloud_model[:3, 3] + rng.normal(0, sigma, points_obj.shape)
    order = rng.permutation(n_cloud)
    where = np.empty(n_cloud, dtype=np.int64)
    where[order] = np.arange(n_cloud)
    truth = {int(k): int(where[i]) for i, k in enumerate(visible_idx)}
    return Case(model=model, cloud=cloud[order], truth=truth, T_cloud_model=T_cloud_model, boxes=boxes,
                seabed_z=seabed_z)


def pose_errors(T_est: Array, T_true: Array) -> tuple[float, float]:
    """Rotation error (deg) and camera-position error in the object frame (m)."""
    angle = rotation_angle_deg(T_est[:3, :3].T @ T_true[:3, :3])
    return angle, float(np.linalg.norm(invert(T_est)[:3, 3] - invert(T_true)[:3, 3]))


def ideal_transform(case: Case) -> Array:
    """The least-squares transform on every true pair: the noise floor no identification can beat."""
    pairs = np.array(sorted(case.truth.items()))
    return rigid_transform(case.model[pairs[:, 0]], case.cloud[pairs[:, 1]])


def score_pairs(pairs: list[tuple[int, int]], truth: dict[int, int]) -> tuple[int, int]:
    """(correct, wrong) pairs against the ground truth."""
    correct = sum(1 for k, j in pairs if truth.get(k) == j)
    return correct, len(pairs) - correct


__all__ = ["EXCLUSION", "SIGMA", "TOLERANCE", "Case", "ideal_transform", "pose_errors", "random_case", "score_pairs"]
