"""Fusing referenced views (seed 000, approach 3): one wrong identification does not pull the fused transform."""

from __future__ import annotations

import numpy as np

from mission.agents.fusion import VIEW_AGREEMENT_M, consistent_views, fuse_views
from mission.frames import pose_matrix
from mission.geometry import rotation_angle_deg, transform_points

MODEL = np.array([[2, 1, -2], [6, 1, -2], [6, 4, -2], [2, 4, -2], [4, 2.5, -2.6]], dtype=float)
T_TRUE = pose_matrix(150.0, 200.0, 58.0, 30.0)


def views(noise: float, count: int, seed: int = 1):
    rng = np.random.default_rng(seed)
    return [(MODEL, transform_points(T_TRUE, MODEL) + rng.normal(0.0, noise, MODEL.shape)) for _ in range(count)]


def test_fused_views_place_the_object_within_a_few_millimetres_of_the_truth():
    fused = fuse_views(views(0.005, 4), VIEW_AGREEMENT_M)
    assert fused is not None and fused.views == 4 and fused.points == 4 * len(MODEL)
    assert np.linalg.norm(fused.T[:3, 3] - T_TRUE[:3, 3]) < 0.01
    assert rotation_angle_deg(fused.T[:3, :3].T @ T_TRUE[:3, :3]) < 0.2
    assert fused.residual_m < 0.01


def test_a_wrong_identification_is_left_out_of_the_fusion():
    good = views(0.003, 3)
    wrong = (MODEL, transform_points(pose_matrix(150.4, 200.0, 58.0, 31.0), MODEL))
    assert len(consistent_views([*good, wrong], VIEW_AGREEMENT_M)) == 3
    fused = fuse_views([good[0], wrong, good[1], good[2]], VIEW_AGREEMENT_M)
    assert fused is not None and fused.views == 3
    assert np.linalg.norm(fused.T[:3, 3] - T_TRUE[:3, 3]) < 0.01


def test_no_fix_while_fewer_than_two_views_agree():
    wrong = (MODEL, transform_points(pose_matrix(151.0, 200.0, 58.0, 30.0), MODEL))
    assert fuse_views([views(0.0, 1)[0], wrong], VIEW_AGREEMENT_M) is None
