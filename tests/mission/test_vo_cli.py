"""`auv eval-traj`, `auv vo` and `auv simulate --record-stereo`: the commands over their public functions."""

from __future__ import annotations

import json
import os
import re
import tempfile
import time
from pathlib import Path
from typing import Any

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("MESA_SHADER_CACHE_DIR", tempfile.mkdtemp(prefix="mesa-cache-"))

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from conftest import WORLD  # noqa: E402
from scipy.spatial.transform import Rotation  # noqa: E402

from mission.cli import main  # noqa: E402
from mission.plugin_api import StereoImages  # noqa: E402
from mission.sim.stereo_record import StereoRecorder  # noqa: E402
from mission.trajectory_eval import evaluate, read_trajectory, write_trajectory  # noqa: E402

KITTI06 = Path("/work/shared/data/kitti06_0-50")


def _walk(seed: int, n: int, noise: float = 0.0) -> np.ndarray:
    """A forward-moving camera; with `noise`, the same motion integrated with drift (an estimate)."""
    rng = np.random.default_rng(seed)
    steps = []
    for _ in range(n - 1):
        T = np.eye(4)
        T[:3, :3] = Rotation.from_rotvec(rng.normal(0, 0.03, 3)).as_matrix()
        T[:3, 3] = [0.0, 0.0, 1.0] + rng.normal(0, 0.05, 3)
        steps.append(T)
    gt, est = [np.eye(4)], [np.eye(4)]
    noise_rng = np.random.default_rng(seed + 1000)
    for T in steps:
        gt.append(gt[-1] @ T)
        E = np.eye(4)
        E[:3, :3] = Rotation.from_rotvec(noise_rng.normal(0, noise / 10, 3)).as_matrix()
        E[:3, 3] = noise_rng.normal(0, noise, 3)
        est.append(est[-1] @ T @ E)
    return np.stack(est if noise else gt)


@pytest.fixture
def trajectories(tmp_path: Path) -> tuple[Path, Path, np.ndarray, np.ndarray]:
    gt, est = _walk(1, 40), _walk(1, 40, noise=0.02)
    write_trajectory(tmp_path / "gt.txt", gt)
    write_trajectory(tmp_path / "est.tum", est, 0.1 * np.arange(40), fmt="tum")
    return tmp_path / "gt.txt", tmp_path / "est.tum", gt, est


# ------------------------------------------------------------------------------------------------------ eval-traj


def test_eval_traj_prints_the_rpe_table_and_the_summary(trajectories: Any, capsys: pytest.CaptureFixture[str]) -> None:
    gt_file, est_file, gt, est = trajectories
    assert main(["eval-traj", str(gt_file), str(est_file)]) == 0
    out = capsys.readouterr().out.splitlines()
    expected = evaluate(gt, est)
    table = [line for line in out if re.fullmatch(r"\s*\d+\s+\d+\s+[\d.]+\s+[\d.]+", line)]
    assert len(table) == 39
    np.testing.assert_allclose([[float(x) for x in row.split()[2:]] for row in table], expected.rpe_per_frame,
                               atol=1e-4)
    text = "\n".join(out)
    assert f"rmse {expected.ate_rmse_m:.4f} m" in text
    assert f"translation rmse {expected.rpe_trans_rmse_m:.4f} m" in text
    assert f"end-point drift: {expected.endpoint_drift_m:.4f} m = {expected.endpoint_drift_percent:.3f} %" in text


def test_eval_traj_json_holds_every_metric(trajectories: Any, capsys: pytest.CaptureFixture[str]) -> None:
    gt_file, est_file, gt, est = trajectories
    assert main(["eval-traj", str(gt_file), str(est_file), "--delta", "4", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    expected = evaluate(gt, est, delta=4)
    assert data["delta"] == 4 and len(data["rpe_per_frame"]) == 36
    for key in ("ate_rmse_m", "ate_mean_m", "ate_max_m", "rpe_trans_rmse_m", "rpe_rot_rmse_deg",
                "endpoint_drift_m", "endpoint_drift_percent", "path_length_m"):
        assert data[key] == pytest.approx(getattr(expected, key), rel=1e-6), key
    assert data["ate_rmse_m"] > 0.01  # the estimate drifts: the figures are not zeros


def test_eval_traj_reports_a_bad_file_in_one_located_line(tmp_path: Path, trajectories: Any,
                                                          capsys: pytest.CaptureFixture[str]) -> None:
    gt_file, _, _, _ = trajectories
    bad = tmp_path / "bad.txt"
    bad.write_text("1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1\n")
    assert main(["eval-traj", str(gt_file), str(bad)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"auv: {bad}:2: expected 12 numbers (KITTI, as above), got 11"]


# ------------------------------------------------------------------------------------------------------------ vo


def _vo_module() -> Any:
    vo = pytest.importorskip("perception_plugins.vo")
    if not hasattr(vo, "read_kitti_sequence"):
        pytest.skip("perception_plugins.vo does not export its API yet")
    return vo


def _synthetic_sequence(folder: Path, poses: np.ndarray) -> None:
    """A KITTI-layout folder (written by the stereo recorder) of random-texture pairs with known poses."""
    rng = np.random.default_rng(5)
    K = np.array([[100.0, 0.0, 32.0], [0.0, 100.0, 24.0], [0.0, 0.0, 1.0]])
    with StereoRecorder(folder) as recorder:
        for i, T in enumerate(poses):
            left = rng.integers(0, 256, (48, 64), dtype=np.uint8)
            recorder.write(StereoImages(0.1 * i, left, np.roll(left, -3, axis=1), K, 0.3), T, T)


def test_vo_writes_the_estimate_with_progress_and_evaluates_it(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                               capsys: pytest.CaptureFixture[str]) -> None:
    vo = _vo_module()
    gt, est = _walk(2, 12), _walk(2, 12, noise=0.05)
    _synthetic_sequence(tmp_path / "seq", gt)
    seen: dict[str, Any] = {}

    def fake_estimator(frames: Any, method: str = "adaptive", progress: Any = None, **_: Any) -> np.ndarray:
        """Stands in for the VO algorithms: reads every frame as the real one would, returns a known estimate."""
        seen["method"], seen["frames"] = method, [f for f in frames]
        for i in range(len(seen["frames"])):
            time.sleep(0.06)  # long enough for the bar to refresh
            progress(i)
        return est

    monkeypatch.setattr(vo, "estimate_trajectory", fake_estimator)
    out = tmp_path / "est.tum"
    assert main(["vo", str(tmp_path / "seq"), "--out", str(out), "--format", "tum", "--method", "klt"]) == 0
    captured = capsys.readouterr()
    assert seen["method"] == "klt" and len(seen["frames"]) == 12
    assert all(isinstance(f, StereoImages) and f.baseline == pytest.approx(0.3) for f in seen["frames"])
    written = read_trajectory(out)
    np.testing.assert_allclose(written.poses, est, atol=1e-8)
    np.testing.assert_allclose(written.times, 0.1 * np.arange(12), atol=1e-9)
    shown = [int(n) for n in re.findall(r"(\d+)/12 \[", captured.err)]  # the progress bar, on stderr
    assert shown and max(shown) > 0 and "frame/s" in captured.err
    expected = evaluate(gt, est)
    assert f"rmse {expected.ate_rmse_m:.4f} m" in captured.out  # poses.txt present: the summary follows
    assert f"end-point drift: {expected.endpoint_drift_m:.4f} m" in captured.out


def test_vo_errors_become_one_line_messages(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    _vo_module()
    assert main(["vo", str(tmp_path / "missing"), "--out", str(tmp_path / "x.txt"), "-q"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("auv: ") and "missing" in err[0]
    (tmp_path / "seq" / "image_0").mkdir(parents=True)
    assert main(["vo", str(tmp_path / "seq"), "--out", str(tmp_path / "x.txt"), "-q"]) == 1
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


@pytest.mark.skipif(not (KITTI06 / "calib.txt").exists(), reason="needs ../shared/data/kitti06_0-50")
def test_vo_tracks_the_kitti_clip_and_evaluates_it_against_its_poses(tmp_path: Path,
                                                                     capsys: pytest.CaptureFixture[str]) -> None:
    _vo_module()
    out = tmp_path / "klt.txt"
    assert main(["vo", str(KITTI06), "--out", str(out), "--method", "klt", "-q"]) == 0
    printed = capsys.readouterr().out
    estimate = read_trajectory(out)
    errors = evaluate(read_trajectory(KITTI06 / "poses.txt"), estimate)
    assert len(estimate) == 51 and f"rmse {errors.ate_rmse_m:.4f} m" in printed
    # 60 m of urban driving: a working stereo VO stays within decimetres (0.10 m ATE and 0.8 % drift measured);
    # a broken one is metres off
    assert errors.ate_rmse_m < 0.5 and errors.endpoint_drift_percent < 3.0
    assert errors.path_length_m == pytest.approx(59.86, abs=0.01)


# ---------------------------------------------------------------------------------------------- simulate --record


MISSION = f"""name: record-cli
world: {WORLD}
home: {{north: 152, east: 202, depth: 50, heading: 30}}
sensors:
  stereo: {{width: 240, height: 180, fx: 200, baseline: 0.25, rate_hz: 10, max_range: 8}}
  usbl: {{sigma: 1.5, rate_hz: 0.5}}
  dvl: {{drift_percent: 0.5}}
plugins: {{referencing: stereo-referencing}}
safety: {{geofence: [[-60, -60], [-60, 460], [360, 460], [360, -60]], max_depth: 120, min_altitude: 1.5}}
objects:
  - id: manifold-1
    pose: {{north: 150, east: 200, depth: 58, heading: 30}}
    size: [8, 5, 2.5]
    characteristic_points:
      - id: module-top
        points: [[2, 1, -2], [6, 1, -2], [6, 4, -2], [2, 4, -2], [4, 2.5, -2.6]]
route:
  - id: reference
    reference: {{object: manifold-1, point_sets: [module-top]}}
    timeout: 25s
"""


def test_simulate_records_stereo_that_eval_traj_and_the_kitti_reader_take(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("cv2")
    (tmp_path / "m.yaml").write_text(MISSION, encoding="utf-8")
    run = tmp_path / "run"
    # the reference element times out (exit 1) after a few captures; the stream is written regardless
    main(["simulate", str(tmp_path / "m.yaml"), "--out", str(run), "--no-plots", "-q", "--record-stereo"])
    out = capsys.readouterr().out
    frames = len((run / "stereo" / "times.txt").read_text().splitlines())
    assert frames >= 2 and f"stereo stream: {frames} pair(s) in {run / 'stereo'}" in out
    # the navigation estimate against the truth, with the same command as any estimate
    assert main(["eval-traj", str(run / "stereo" / "poses.txt"), str(run / "stereo" / "nav.txt"), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    truth, nav = read_trajectory(run / "stereo" / "poses.txt"), read_trajectory(run / "stereo" / "nav.txt")
    assert data["ate_rmse_m"] == pytest.approx(evaluate(truth, nav).ate_rmse_m, rel=1e-9)
    assert 0.0 < data["ate_max_m"] < 10.0
    vo = pytest.importorskip("perception_plugins.vo")
    if hasattr(vo, "read_kitti_sequence"):
        sequence = vo.read_kitti_sequence(run / "stereo")
        assert len(sequence) == frames
        np.testing.assert_allclose(sequence.gt_poses, truth.poses)
