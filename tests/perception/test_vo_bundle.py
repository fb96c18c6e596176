"""The local bundle adjustment: on a synthetic stereo scene through a 70° turn (points and poses known, pixel noise,
outliers and perturbed poses), it lowers the reprojection error and recovers the poses; the keyframe window links
landmarks across keyframes and returns adjusted poses."""

from __future__ import annotations

import numpy as np
import pytest

from mission.geometry import invert
from perception_plugins.vo.bundle import BundleError, Observations, bundle_adjust
from perception_plugins.vo.se3 import from_rotvec_translation
from perception_plugins.vo.window import KeyFeatures, KeyframeWindow, Matches, WindowSettings

K = np.array([[700.0, 0.0, 613.0], [0.0, 700.0, 185.0], [0.0, 0.0, 1.0]])
BASELINE = 0.54
SIZE = (1226, 370)


def _turning_poses(count: int = 8, turn_deg: float = 10.0, step_m: float = 1.0) -> np.ndarray:
    """T_world_cam of a camera driving forward (z) and turning about its y axis by `turn_deg` per keyframe."""
    poses, position, yaw = [], np.zeros(3), 0.0
    for _ in range(count):
        T = from_rotvec_translation([0.0, yaw, 0.0], position)
        poses.append(T)
        position = position + step_m * T[:3, 2]
        yaw += np.radians(turn_deg)
    return np.stack(poses)


def _project(T_world_cam: np.ndarray, X: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    p = X @ invert(T_world_cam)[:3, :3].T + invert(T_world_cam)[:3, 3]
    z = np.where(p[:, 2] > 0.5, p[:, 2], np.nan)
    left = np.column_stack([K[0, 0] * p[:, 0] / z + K[0, 2], K[1, 1] * p[:, 1] / z + K[1, 2]])
    right = left.copy()
    right[:, 0] -= K[0, 0] * BASELINE / z
    inside = np.isfinite(z) & (right[:, 0] >= 0) & (left[:, 0] < SIZE[0]) & (left[:, 1] >= 0) & (left[:, 1] < SIZE[1])
    return left, right, inside


def _scene(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, Observations]:
    poses = _turning_poses()
    X = rng.uniform([-40.0, -3.0, -40.0], [40.0, 2.0, 40.0], (5000, 3))
    rows = []
    for k, T in enumerate(poses):
        left, right, inside = _project(T, X)
        for i in np.flatnonzero(inside):
            rows.append((k, i, *left[i], *right[i]))
    a = np.array(rows)
    counts = np.bincount(a[:, 1].astype(int), minlength=len(X))
    a = a[counts[a[:, 1].astype(int)] >= 2]
    used, point = np.unique(a[:, 1].astype(int), return_inverse=True)
    obs = Observations(a[:, 0].astype(int), point, a[:, 2:4], a[:, 4:6])
    return poses, X[used], obs


def _position_errors(estimated: np.ndarray, truth: np.ndarray) -> np.ndarray:
    return np.asarray(np.linalg.norm(estimated[:, :3, 3] - truth[:, :3, 3], axis=1))


def test_bundle_adjustment_recovers_the_poses_of_a_turn_from_noisy_pixels_and_perturbed_poses() -> None:
    rng = np.random.default_rng(1)
    poses, X, obs = _scene(rng)
    noisy_left = obs.uv_left + rng.normal(0.0, 0.3, obs.uv_left.shape)
    noisy_right = obs.uv_right + rng.normal(0.0, 0.3, obs.uv_right.shape)
    noisy_right[rng.random(len(obs)) < 0.3] = np.nan  # features without a right match
    outliers = rng.random(len(obs)) < 0.03
    noisy_left[outliers] += rng.normal(0.0, 25.0, (int(outliers.sum()), 2))
    start = poses.copy()
    for k in range(1, len(poses)):
        start[k] = poses[k] @ from_rotvec_translation(rng.normal(0.0, 0.01, 3), rng.normal(0.0, 0.1, 3))
    result = bundle_adjust(start, X + rng.normal(0.0, 0.2, X.shape),
                           Observations(obs.keyframe, obs.point, noisy_left, noisy_right), K, BASELINE)
    assert np.allclose(result.T_world_cam[0], poses[0])  # the fixed keyframe stays
    assert _position_errors(start, poses)[1:].min() > 0.03
    assert _position_errors(result.T_world_cam, poses).max() < 0.01  # 1 cm after, from up to ~0.2 m
    # the inliers' error drops to the pixel noise (0.3 px per coordinate: ~0.4 px per observation, ~0.6 for both)
    assert np.median(result.error_px[~outliers]) < 0.7
    assert result.rms_after_px < 0.5 * result.rms_before_px


def test_bundle_adjustment_refuses_observations_of_unknown_points() -> None:
    rng = np.random.default_rng(2)
    poses, X, obs = _scene(rng)
    with pytest.raises(BundleError):
        bundle_adjust(poses, X[:10], obs, K, BASELINE)


def test_the_window_links_landmarks_across_keyframes_and_corrects_a_drifting_front_end() -> None:
    """A front end whose every step is 2 % too long (a scale drift) and turns 0.3° too far: the window, fed the true
    pixels of landmarks that live over several keyframes, brings the newest keyframe back near the truth."""
    rng = np.random.default_rng(3)
    poses = _turning_poses(count=12, turn_deg=8.0)
    X = rng.uniform([-40.0, -3.0, -40.0], [40.0, 2.0, 60.0], (6000, 3))
    window = KeyframeWindow(WindowSettings(size=6))
    previous: tuple[np.ndarray, np.ndarray] | None = None  # the last keyframe's point indices and pixels
    T_front = poses[0]
    adjusted = [poses[0]]
    for k, T in enumerate(poses):
        left, right, inside = _project(T, X)
        index = np.flatnonzero(inside)[:400]
        noise = rng.normal(0.0, 0.2, (len(index), 2))
        features = KeyFeatures(left[index] + noise, right[index] + noise,
                               np.zeros((len(index), 3)))
        # the features' points as triangulated at this keyframe (in its camera frame)
        features = KeyFeatures(features.uv_left, features.uv_right,
                               X[index] @ invert(T)[:3, :3].T + invert(T)[:3, 3])
        matches = None
        if previous is not None:
            prev_index, _ = previous
            seen = np.flatnonzero(inside[prev_index])
            matches = Matches(seen, left[prev_index[seen]], right[prev_index[seen]])
            step = invert(poses[k - 1]) @ T
            wrong = from_rotvec_translation([0.0, np.radians(0.3), 0.0], 1.02 * step[:3, 3])
            wrong[:3, :3] = step[:3, :3] @ wrong[:3, :3]
            T_front = adjusted[-1] @ wrong
        out = window.add(T_front, features, matches, K, BASELINE)
        if k:
            adjusted.append(out)
        previous = (index, left[index])
    final_front = np.linalg.norm(T_front[:3, 3] - poses[-1][:3, 3])
    err = _position_errors(np.stack(adjusted), poses)
    assert window.stats.adjustments == len(poses) - 1
    assert final_front > 0.015  # the front end's own step is off by 2 cm and more
    assert err.max() < 0.01
