"""Relative motions between the frames of a stereo recording, measured by stereo odometry's classic scheme (seed
003: features matched across the four images of two pairs, PnP-RANSAC on both images of the second), for the
pose graph (`pose_graph.anchor_poses`).

Which pairs are measured: every frame with the next two (the odometry chain), and revisits — frames at least
`revisit_gap` apart whose views aim at the same place (the points `aim_m` along their optical axes within
`revisit_radius_m`, the views turned by at most `revisit_turn_deg`), at most `revisits` per frame, the ones
farthest apart in time first. A revisit edge ties together two passes over the same surface, which the chain
alone would let drift apart.

A measured motion is kept when at least `min_inliers` features support it and it agrees with the navigation's
relative motion within the navigation's possible error (`gate_m` + `gate_per_s` · the time between them, and
`gate_deg`): a wrong match on repetitive texture is refused here before it reaches the graph.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mission.plugin_api import StereoImages
from perception_plugins.reconstruction.pose_graph import Edge
from perception_plugins.stereo import Cloud, Detector
from perception_plugins.vo.classic import describe, match_descriptors
from perception_plugins.vo.motion import estimate_motion

Array = NDArray[np.float64]


@dataclass(frozen=True)
class MotionSettings:
    features: int = 1500
    chain_detector: Detector = "harris"
    """The odometry's sub-pixel Harris corners between near frames (on the loop's explore recording: 1.5 mm median
    error a step, ORB's whole-pixel keypoints 5.3 mm)."""
    revisit_detector: Detector = "orb"
    """ORB's own oriented keypoints for revisits: those see the surface turned by up to `revisit_turn_deg`, and
    unoriented Harris corners matched 26–44 of 1200 features there (ORB: 250–480)."""
    min_inliers: int = 25
    threshold_px: float = 1.5
    chain: int = 2
    """Each frame is measured against this many following frames."""
    revisits: int = 2
    revisit_gap: int = 20
    revisit_radius_m: float = 1.5
    revisit_turn_deg: float = 30.0
    aim_m: float = 6.0
    gate_m: float = 0.5
    gate_per_s: float = 0.01
    gate_deg: float = 3.0


def candidate_pairs(nav: Array, times: Array, settings: MotionSettings | None = None) -> list[tuple[int, int]]:
    """The frame pairs to measure (module docstring), from the navigation poses (N, 4, 4) T_world_cam."""
    s = settings or MotionSettings()
    n = len(nav)
    pairs = [(i, j) for i in range(n) for j in range(i + 1, min(n, i + 1 + s.chain))]
    aims = nav[:, :3, 3] + s.aim_m * nav[:, :3, 2]
    cos_turn = np.cos(np.radians(s.revisit_turn_deg))
    for i in range(n):
        later = np.arange(i + s.revisit_gap, n)
        if len(later) == 0:
            break
        near = np.linalg.norm(aims[later] - aims[i], axis=1) < s.revisit_radius_m
        turn_cos = (np.einsum("ab,kab->k", nav[i, :3, :3], nav[later, :3, :3]) - 1.0) / 2.0  # (tr(R_iᵀR_j) − 1) / 2
        aligned = turn_cos > cos_turn
        chosen = later[near & aligned]
        if len(chosen):
            far_first = chosen[np.argsort(times[i] - times[chosen])][: s.revisits]
            pairs.extend((i, int(j)) for j in far_first)
    return pairs


def measure_motions(load: Callable[[int], StereoImages], nav: Array, times: Array,
                    pairs: Sequence[tuple[int, int]], settings: MotionSettings | None = None) -> list[Edge]:
    """The relative motions of `pairs` that pass the checks (module docstring). `load(k)` gives frame k; each frame
    is described once."""
    s = settings or MotionSettings()
    clouds: dict[tuple[int, Detector], Cloud] = {}
    K = baseline = None

    def cloud(k: int, detector: Detector) -> Cloud:
        nonlocal K, baseline
        if (k, detector) not in clouds:
            frame = load(k)
            K, baseline = frame.K, frame.baseline
            clouds[k, detector] = describe(frame, s.features, detector=detector)
        return clouds[k, detector]

    edges = []
    for i, j in pairs:
        detector = s.chain_detector if j - i <= s.chain else s.revisit_detector
        a, b = cloud(i, detector), cloud(j, detector)
        guess = np.linalg.inv(nav[i]) @ nav[j]
        ia, ib = match_descriptors(a.descriptors, b.descriptors)
        assert K is not None and baseline is not None
        motion = estimate_motion(a.points_cam[ia], b.uv_left[ib], K, uv_b_right=b.uv_right[ib], baseline=baseline,
                                 T_a_b_guess=guess, threshold_px=s.threshold_px, min_inliers=s.min_inliers)
        if motion is None or motion.count < s.min_inliers:
            continue
        T = motion.T_a_b
        moved = float(np.linalg.norm(T[:3, 3] - guess[:3, 3]))
        turned = float(np.degrees(np.arccos(np.clip((np.trace(guess[:3, :3].T @ T[:3, :3]) - 1.0) / 2.0, -1, 1))))
        if moved <= s.gate_m + s.gate_per_s * abs(times[j] - times[i]) and turned <= s.gate_deg:
            edges.append(Edge(i, j, T, motion.count))
    return edges


__all__ = ["MotionSettings", "candidate_pairs", "measure_motions"]
