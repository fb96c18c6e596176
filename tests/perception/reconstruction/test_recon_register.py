"""Pose refinement by point-to-plane ICP against the surface already placed."""

from __future__ import annotations

import numpy as np

from perception_plugins.reconstruction import RangeMap
from perception_plugins.reconstruction.register import points_and_normals, refine_pose


def _staircase_map() -> RangeMap:
    """A camera 4 m above three steps and a ramp (enough relief to fix all six degrees of freedom)."""
    K = np.array([[200.0, 0, 99.5], [0, 200.0, 79.5], [0, 0, 1]])
    u, v = np.meshgrid(np.arange(200), np.arange(160))
    depth = 4.0 - 0.3 * (u // 60) - 0.002 * v - 0.2 * ((u - 100) ** 2 + (v - 80) ** 2 < 900)
    depth = depth.astype(np.float32)
    return RangeMap(depth, np.full_like(depth, 0.01), K, np.zeros_like(depth))


def test_a_displaced_pose_is_brought_back_onto_the_surface() -> None:
    rmap = _staircase_map()
    points, normals = points_and_normals(rmap, stride=2)
    T_true = np.eye(4)
    model = points @ T_true[:3, :3].T
    c, s = np.cos(np.radians(1.0)), np.sin(np.radians(1.0))
    T_prior = np.eye(4)
    T_prior[:3, :3] = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    T_prior[:3, 3] = (0.04, -0.03, 0.02)
    T, matched = refine_pose(points, T_prior, model, normals)
    assert matched > 1000
    assert np.linalg.norm(T[:3, 3] - T_true[:3, 3]) < 0.005
    assert np.degrees(np.arccos(np.clip((np.trace(T[:3, :3]) - 1) / 2, -1, 1))) < 0.1


def test_without_overlap_the_prior_is_kept() -> None:
    rmap = _staircase_map()
    points, normals = points_and_normals(rmap, stride=4)
    T_prior = np.eye(4)
    T_prior[:3, 3] = (50.0, 0.0, 0.0)
    T, matched = refine_pose(points, T_prior, points, normals)
    assert matched == 0 and np.array_equal(T, T_prior)
