"""Trajectory files and metrics (mission/trajectory_eval.py): hand-built cases with known answers, and evo."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from mission.errors import AuvError
from mission.trajectory_eval import (
    Trajectory,
    TrajectoryError,
    align_se3,
    evaluate,
    read_trajectory,
    write_trajectory,
)

KITTI06 = Path("/work/shared/data/kitti06_0-50/poses.txt")


def _pose(R: np.ndarray, t: np.ndarray) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, t
    return T


def _straight_line(n: int, step: float) -> np.ndarray:
    """n poses along x, identity attitude, `step` metres apart."""
    return np.stack([_pose(np.eye(3), np.array([i * step, 0.0, 0.0])) for i in range(n)])


def _random_walk(rng: np.random.Generator, n: int) -> np.ndarray:
    """A camera moving ~1 m a frame forward with small random turns, as a VO sequence does."""
    T = [np.eye(4)]
    for _ in range(n - 1):
        turn = Rotation.from_rotvec(rng.normal(0, 0.05, 3)).as_matrix()
        T.append(T[-1] @ _pose(turn, np.array([0, 0, 1.0]) + rng.normal(0, 0.1, 3)))
    return np.stack(T)


def _perturbed(rng: np.random.Generator, gt: np.ndarray, sigma_t: float, sigma_r: float) -> np.ndarray:
    """An estimate that integrates the ground truth's relative motions with noise (drifts like VO), then is moved
    by an arbitrary rigid motion (its own world frame)."""
    est = [np.eye(4)]
    for a, b in zip(gt[:-1], gt[1:], strict=True):
        rel = np.linalg.inv(a) @ b
        noise = _pose(Rotation.from_rotvec(rng.normal(0, sigma_r, 3)).as_matrix(), rng.normal(0, sigma_t, 3))
        est.append(est[-1] @ rel @ noise)
    offset = _pose(Rotation.from_rotvec(rng.normal(0, 0.5, 3)).as_matrix(), rng.normal(0, 5, 3))
    return np.einsum("ij,njk->nik", offset, np.stack(est))


# ------------------------------------------------------------------------------------------------- hand-built cases


def test_pure_translation_offset_has_zero_ate_rpe_and_drift() -> None:
    gt = _random_walk(np.random.default_rng(0), 40)
    est = gt.copy()
    est[:, :3, 3] += [3.0, -2.0, 7.5]
    errors = evaluate(gt, est)
    assert errors.ate_rmse_m < 1e-9 and errors.ate_max_m < 1e-9
    assert errors.rpe_trans_rmse_m < 1e-9 and errors.rpe_rot_rmse_deg < 1e-6
    assert errors.endpoint_drift_m < 1e-9
    assert errors.rpe_per_frame.shape == (39, 2)


def test_align_se3_recovers_a_known_rigid_motion() -> None:
    rng = np.random.default_rng(1)
    est = rng.normal(0, 10, (30, 3))
    R_true = Rotation.from_rotvec([0.3, -1.2, 2.0]).as_matrix()
    t_true = np.array([4.0, -1.0, 9.0])
    R, t = align_se3(est @ R_true.T + t_true, est)
    np.testing.assert_allclose(R, R_true, atol=1e-12)
    np.testing.assert_allclose(t, t_true, atol=1e-11)


def test_known_constant_drift_gives_known_endpoint_percent() -> None:
    # 100 m straight; the estimate slides 1 cm sideways per metre travelled: 1 m off at the end = 1 % of the path
    gt = _straight_line(101, 1.0)
    est = gt.copy()
    est[:, 1, 3] += 0.01 * np.arange(101)
    errors = evaluate(gt, est)
    assert errors.path_length_m == pytest.approx(100.0)
    assert errors.endpoint_drift_m == pytest.approx(1.0, rel=1e-12)
    assert errors.endpoint_drift_percent == pytest.approx(1.0, rel=1e-12)
    # every frame-to-frame translation is off by exactly 1 cm, attitude never
    np.testing.assert_allclose(errors.rpe_per_frame[:, 0], 0.01, rtol=1e-9)
    np.testing.assert_allclose(errors.rpe_per_frame[:, 1], 0.0, atol=1e-9)
    # alignment turns the slanted line onto the truth; what is left is its stretch, (√1.0001 − 1) per metre,
    # about the middle frame
    stretch = math.sqrt(1.0001) - 1.0
    assert errors.ate_rmse_m == pytest.approx(stretch * np.std(np.arange(101)), rel=1e-6)
    assert errors.ate_max_m == pytest.approx(stretch * 50.0, rel=1e-6)


def test_heading_error_at_the_start_rotates_the_path_about_the_start() -> None:
    # the first step is estimated 5° off in yaw; everything after is right, so the path swings about its start
    theta = math.radians(5.0)
    length = 50.0
    gt = _straight_line(51, 1.0)
    Rz = _pose(Rotation.from_euler("z", theta).as_matrix(), np.zeros(3))
    est = np.einsum("ij,njk->nik", Rz, gt)
    est[0] = gt[0]
    errors = evaluate(gt, est)
    chord = 2.0 * length * math.sin(theta / 2.0)
    assert errors.endpoint_drift_m == pytest.approx(chord, rel=1e-12)
    assert errors.endpoint_drift_percent == pytest.approx(100.0 * chord / length, rel=1e-12)
    # only the first pair is wrong: by the angle, and by the chord of one 1 m step
    assert errors.rpe_per_frame[0, 1] == pytest.approx(5.0, rel=1e-9)
    assert errors.rpe_per_frame[0, 0] == pytest.approx(2.0 * math.sin(theta / 2.0), rel=1e-9)
    np.testing.assert_allclose(errors.rpe_per_frame[1:], 0.0, atol=1e-9)
    # undoing the rotation maps every position onto the truth (the start lies on its axis): ATE after alignment 0
    assert errors.ate_rmse_m < 1e-9


def test_ate_alignment_is_optimal_among_rigid_motions() -> None:
    rng = np.random.default_rng(2)
    gt = _random_walk(rng, 60)
    est = _perturbed(rng, gt, 0.05, 0.01)
    errors = evaluate(gt, est)
    R, t = align_se3(gt[:, :3, 3], est[:, :3, 3])
    aligned = est[:, :3, 3] @ R.T + t
    for _ in range(20):  # nudge the optimum: the error can only grow
        dR = Rotation.from_rotvec(rng.normal(0, 1e-3, 3)).as_matrix()
        moved = aligned @ dR.T + rng.normal(0, 1e-3, 3)
        rmse = math.sqrt(np.mean(np.sum((moved - gt[:, :3, 3]) ** 2, axis=1)))
        assert rmse >= errors.ate_rmse_m


# ---------------------------------------------------------------------------------------------------- files


def test_kitti_and_tum_files_round_trip(tmp_path: Path) -> None:
    gt = _random_walk(np.random.default_rng(3), 25)
    times = 0.1 * np.arange(25) + 1000.0
    write_trajectory(tmp_path / "a.txt", gt)
    write_trajectory(tmp_path / "b.tum", gt, times, fmt="tum")
    kitti, tum = read_trajectory(tmp_path / "a.txt"), read_trajectory(tmp_path / "b.tum")
    assert kitti.times is None
    np.testing.assert_allclose(kitti.poses, gt, atol=1e-8)
    np.testing.assert_allclose(tum.poses, gt, atol=1e-8)
    np.testing.assert_allclose(tum.times, times, atol=1e-9)


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("1 2 3\n", "a.txt:1: expected 12 numbers (KITTI 3×4 pose) or 8"),
        ("1 0 0 0 0 1 0 0 0 0 1 0\n\n1 0 0 0 0 1 0 0 0 0 1\n",
         "a.txt:3: expected 12 numbers (KITTI, as above), got 11"),
        ("# t x y z qx qy qz qw\n0 0 0 0 0 0 0 1\n1 0 0 x 0 0 0 1\n", "a.txt:3: not a number: 'x'"),
        ("0 0 0 0 0 0 0 2\n", "a.txt:1: quaternion qx qy qz qw has norm 2"),
        ("1 0 0 0 0 1 0 0 0 0 1 0\n2 0 0 0 0 1 0 0 0 0 1 0\n", "a.txt:2: the 3×3 part is not a rotation matrix"),
        ("0 0 0 0 0 0 0 1\n0 0 0 0 0 0 0 1\n", "a.txt:2: timestamps must increase"),
        ("# nothing\n", "a.txt: no poses"),
    ],
)
def test_bad_files_give_located_errors(tmp_path: Path, content: str, message: str) -> None:
    (tmp_path / "a.txt").write_text(content)
    with pytest.raises(TrajectoryError) as info:
        read_trajectory(tmp_path / "a.txt")
    assert isinstance(info.value, AuvError)
    assert message in str(info.value)


def test_unequal_lengths_need_timestamps() -> None:
    gt = _straight_line(10, 1.0)
    with pytest.raises(TrajectoryError, match="need timestamps"):
        evaluate(gt, gt[:8])
    with pytest.raises(TrajectoryError, match="delta must be between 1 and 9"):
        evaluate(gt, gt, delta=10)
    with pytest.raises(TrajectoryError, match="timestamps must increase"):
        evaluate(gt, gt[:8], gt_times=np.arange(10.0), est_times=np.arange(8.0)[::-1])


def test_timestamps_associate_a_sparser_estimate() -> None:
    gt = _straight_line(101, 0.5)
    t_gt = 0.1 * np.arange(101)
    keep = np.arange(0, 101, 3)
    est = Trajectory(gt[keep], t_gt[keep] + 0.004)  # a third of the frames, 4 ms late
    errors = evaluate(Trajectory(gt, t_gt), est)
    assert errors.pairs == len(keep)
    assert errors.ate_max_m < 1e-9
    assert errors.path_length_m == pytest.approx(0.5 * keep[-1])


# ------------------------------------------------------------------------------------------------ against evo


def _evo_metrics(gt: np.ndarray, est: np.ndarray, delta: int) -> dict[str, float]:
    evo_traj = pytest.importorskip("evo.core.trajectory")
    evo_metrics = pytest.importorskip("evo.core.metrics")
    import copy

    ref = evo_traj.PosePath3D(poses_se3=list(gt))
    aligned = evo_traj.PosePath3D(poses_se3=list(est))
    aligned.align(ref, correct_scale=False)
    ape = evo_metrics.APE(evo_metrics.PoseRelation.translation_part)
    ape.process_data((ref, aligned))
    out = {
        "ate_rmse_m": ape.get_statistic(evo_metrics.StatisticsType.rmse),
        "ate_mean_m": ape.get_statistic(evo_metrics.StatisticsType.mean),
        "ate_max_m": ape.get_statistic(evo_metrics.StatisticsType.max),
    }
    for relation, key in [
        (evo_metrics.PoseRelation.translation_part, "rpe_trans_rmse_m"),
        (evo_metrics.PoseRelation.rotation_angle_deg, "rpe_rot_rmse_deg"),
    ]:
        rpe = evo_metrics.RPE(relation, delta=delta, delta_unit=evo_metrics.Unit.frames, all_pairs=True)
        rpe.process_data((ref, evo_traj.PosePath3D(poses_se3=list(est))))
        out[key] = rpe.get_statistic(evo_metrics.StatisticsType.rmse)
        out[key + "_per_frame"] = rpe.error
    anchored = copy.deepcopy(evo_traj.PosePath3D(poses_se3=list(est)))
    anchored.align_origin(ref)
    out["endpoint_drift_m"] = float(np.linalg.norm(anchored.positions_xyz[-1] - ref.positions_xyz[-1]))
    out["path_length_m"] = ref.path_length
    return out


def _assert_agrees_with_evo(gt: np.ndarray, est: np.ndarray, delta: int) -> None:
    ours = evaluate(gt, est, delta=delta)
    theirs = _evo_metrics(gt, est, delta)
    for key in ("ate_rmse_m", "ate_mean_m", "ate_max_m", "rpe_trans_rmse_m", "rpe_rot_rmse_deg",
                "endpoint_drift_m", "path_length_m"):
        assert getattr(ours, key) == pytest.approx(theirs[key], rel=1e-6), key
    np.testing.assert_allclose(ours.rpe_per_frame[:, 0], theirs["rpe_trans_rmse_m_per_frame"], rtol=1e-6)
    np.testing.assert_allclose(ours.rpe_per_frame[:, 1], theirs["rpe_rot_rmse_deg_per_frame"], rtol=1e-6)
    # the errors are not trivially zero, so agreement means something
    assert ours.ate_rmse_m > 1e-3 and ours.rpe_rot_rmse_deg > 1e-3 and ours.endpoint_drift_m > 1e-3


@pytest.mark.parametrize(("seed", "delta"), [(10, 1), (11, 1), (12, 5)])
def test_metrics_agree_with_evo_on_random_walks(seed: int, delta: int) -> None:
    rng = np.random.default_rng(seed)
    gt = _random_walk(rng, 200)
    _assert_agrees_with_evo(gt, _perturbed(rng, gt, 0.03, 0.004), delta)


@pytest.mark.skipif(not KITTI06.exists(), reason="needs ../shared/data/kitti06_0-50")
@pytest.mark.parametrize("delta", [1, 10])
def test_metrics_agree_with_evo_on_kitti_ground_truth(delta: int) -> None:
    gt = read_trajectory(KITTI06).poses
    est = _perturbed(np.random.default_rng(20), gt, 0.02, 0.002)
    _assert_agrees_with_evo(gt, est, delta)


def test_reader_agrees_with_evo_and_timestamp_association_too(tmp_path: Path) -> None:
    file_interface = pytest.importorskip("evo.tools.file_interface")
    evo_sync = pytest.importorskip("evo.core.sync")
    evo_metrics = pytest.importorskip("evo.core.metrics")
    rng = np.random.default_rng(30)
    gt = _random_walk(rng, 150)
    est = _perturbed(rng, gt, 0.03, 0.004)
    t_gt = 100.0 + 0.1 * np.arange(150)
    keep = np.sort(rng.choice(150, 90, replace=False))  # the estimate lost frames, and its clock jitters
    t_est = t_gt[keep] + rng.uniform(-0.004, 0.004, len(keep))
    write_trajectory(tmp_path / "gt.tum", gt, t_gt, fmt="tum")
    write_trajectory(tmp_path / "est.tum", est[keep], t_est, fmt="tum")

    ref = file_interface.read_tum_trajectory_file(str(tmp_path / "gt.tum"))
    their_est = file_interface.read_tum_trajectory_file(str(tmp_path / "est.tum"))
    ours_gt, ours_est = read_trajectory(tmp_path / "gt.tum"), read_trajectory(tmp_path / "est.tum")
    np.testing.assert_allclose(ours_gt.poses, np.stack(ref.poses_se3), atol=1e-12)
    np.testing.assert_allclose(ours_est.times, their_est.timestamps, atol=0)

    ref, their_est = evo_sync.associate_trajectories(ref, their_est, max_diff=0.01)
    their_est.align(ref)
    ape = evo_metrics.APE(evo_metrics.PoseRelation.translation_part)
    ape.process_data((ref, their_est))
    ours = evaluate(ours_gt, ours_est)
    assert ours.pairs == len(keep)
    assert ours.ate_rmse_m == pytest.approx(ape.get_statistic(evo_metrics.StatisticsType.rmse), rel=1e-6)
    assert ours.path_length_m == pytest.approx(ref.path_length, rel=1e-9)
