"""`simulate(..., record_stereo=True)` (mission/sim/stereo_record.py): a short referencing run's stereo stream
written in the KITTI odometry layout, read back and checked against the simulator's own log and a re-render."""

from __future__ import annotations

import math
import os
import tempfile
from pathlib import Path
from typing import Any

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("MESA_SHADER_CACHE_DIR", tempfile.mkdtemp(prefix="mesa-cache-"))

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from mission import load_mission, simulate  # noqa: E402
from mission.errors import AuvError  # noqa: E402
from mission.frames import camera_pose  # noqa: E402
from mission.sim.camera import intrinsics  # noqa: E402
from mission.sim.stereo_record import StereoRecording, read_stereo_recording  # noqa: E402
from mission.sim.vehicle import TRAJECTORY_COLUMNS  # noqa: E402

WORLD = Path(__file__).resolve().parents[3] / "worlds" / "sps_field.yaml"

# Start 3 m from manifold-1's database position and reference it with small images, for 40 s: a few search and
# fine captures (the agent turns the camera on only while capturing), in a few seconds of wall time.
MISSION = f"""
name: stereo-record
world: {WORLD}
seed: 5
home: {{north: 152, east: 202, depth: 50, heading: 30}}
sensors:
  stereo: {{width: 320, height: 240, fx: 270, baseline: 0.25, rate_hz: 10, max_range: 8}}
  usbl: {{sigma: 1.5, rate_hz: 0.5}}
  dvl: {{drift_percent: 0.5}}
plugins:
  referencing: stereo-referencing
safety:
  geofence: [[-60, -60], [-60, 460], [360, 460], [360, -60]]
  max_depth: 120
  min_altitude: 1.5
  max_duration: 10min
objects:
  - id: manifold-1
    pose: {{north: 150, east: 200, depth: 58, heading: 30}}
    size: [8, 5, 2.5]
    characteristic_points:
      - id: module-top
        points: [[2, 1, -2], [6, 1, -2], [6, 4, -2], [2, 4, -2], [4, 2.5, -2.6]]
route:
  - id: reference
    reference: {{object: manifold-1, point_sets: [module-top], altitude: 3.6}}
    timeout: 40s
"""


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> Any:
    pytest.importorskip("cv2")
    path = tmp_path_factory.mktemp("stereo") / "stereo_record.yaml"
    path.write_text(MISSION, encoding="utf-8")
    return simulate(load_mission(path), out=path.parent / "run", plots=False, record_stereo=True)


@pytest.fixture(scope="module")
def recording(run: Any) -> StereoRecording:
    return read_stereo_recording(run.out / "stereo")


def test_every_captured_pair_is_recorded_with_the_simulators_true_pose(run: Any, recording: StereoRecording) -> None:
    log = run.vehicle.log.frames
    assert len(log) >= 3 and len(recording) == len(log)
    np.testing.assert_allclose(recording.times, [t for t, _ in log], atol=1e-6)
    np.testing.assert_allclose(recording.poses, np.stack([T for _, T in log]), atol=1e-6)
    # world = the mission's local NED frame: the camera looks down (optical axis = +z, down) near the manifold
    assert np.all(recording.poses[:, 2, 2] > 0.99)
    assert np.all(np.hypot(recording.poses[:, 0, 3] - 150, recording.poses[:, 1, 3] - 200) < 10)


def test_images_and_calibration_are_the_cameras(run: Any, recording: StereoRecording) -> None:
    settings = run.vehicle.mission.sensors.stereo
    np.testing.assert_allclose(recording.K, intrinsics(settings), atol=1e-9)
    assert recording.baseline == pytest.approx(0.25, abs=1e-12)
    calib = (recording.folder / "calib.txt").read_text().splitlines()
    assert [line.split(":")[0] for line in calib] == ["P0", "P1"]
    assert float(calib[1].split()[4]) == pytest.approx(-settings.fx * 0.25)  # P1's 4th column: −fx·baseline
    for i in range(len(recording)):
        left, right = recording.images(i)
        assert left.dtype == np.uint8 and left.shape == (240, 320) and right.shape == (240, 320)
        assert np.abs(left.astype(int) - right.astype(int)).mean() > 1.0  # two viewpoints, not one image twice


def test_recorded_geometry_explains_the_images(run: Any, recording: StereoRecording) -> None:
    """Re-render the last pair from its recorded true pose: the same left image comes out, and warping the right
    image by the disparity fx·b/Z that calib.txt implies reproduces the left one better than any other baseline."""
    import cv2

    from mission.sim.camera import StereoCamera
    from mission.sim.mjworld import mjworld_for

    with StereoCamera(mjworld_for(run.scene), run.vehicle.mission.sensors.stereo, texture=run.scene.texture) as cam:
        frame = cam.render(recording.poses[-1])
    left, right = recording.images(len(recording) - 1)
    assert np.abs(frame.left.astype(int) - left.astype(int)).mean() < 1.0
    disparity = recording.K[0, 0] * recording.baseline / frame.depth_left
    h, w = left.shape
    u, v = np.meshgrid(np.arange(w, dtype=np.float32), np.arange(h, dtype=np.float32))
    errors = {}
    for scale in (1.0, -1.0, 0.0, 0.8, 1.25):  # the recorded baseline, the wrong sign, none, ±20 %
        map_x = (u - scale * disparity).astype(np.float32)
        warped = cv2.remap(right, map_x, v, cv2.INTER_LINEAR)
        valid = np.isfinite(disparity) & (map_x > 1) & (map_x < w - 2)
        errors[scale] = float(np.abs(warped[valid].astype(float) - left[valid].astype(float)).mean())
    assert errors[1.0] < 3.0, errors
    assert all(errors[1.0] < 0.7 * e for scale, e in errors.items() if scale != 1.0), errors


def test_nav_poses_are_the_navigation_estimate_at_each_pair(run: Any, recording: StereoRecording) -> None:
    rows = {round(r[0], 6): r for r in run.vehicle.log.rows}
    col = {name: i for i, name in enumerate(TRAJECTORY_COLUMNS)}
    position_errors = []
    for t, T_nav, T_true in zip(recording.times, recording.nav_poses, recording.poses, strict=True):
        r = rows[round(float(t), 6)]
        expected = camera_pose(r[col["north_est"]], r[col["east_est"]], r[col["depth_est"]], r[col["heading_est"]],
                               baseline=recording.baseline)
        np.testing.assert_allclose(T_nav, expected, atol=1e-6)
        position_errors.append(float(np.linalg.norm(T_nav[:3, 3] - T_true[:3, 3])))
    # an estimate, not the truth: off by the navigation error (USBL σ 1.5 m), but not by tens of metres
    assert 0.0 < max(position_errors) < 10.0 and not math.isclose(max(position_errors), 0.0)


def test_the_kitti_reader_of_the_vo_package_reads_the_recording(recording: StereoRecording) -> None:
    vo = pytest.importorskip("perception_plugins.vo")
    if not hasattr(vo, "read_kitti_sequence"):
        pytest.skip("perception_plugins.vo has no read_kitti_sequence yet")
    sequence = vo.read_kitti_sequence(recording.folder)
    assert len(sequence) == len(recording)
    np.testing.assert_allclose(sequence.K, recording.K)
    assert sequence.baseline == pytest.approx(recording.baseline)
    np.testing.assert_allclose(sequence.gt_poses, recording.poses)
    first = next(iter(sequence))
    np.testing.assert_array_equal(first.left, recording.images(0)[0])
    np.testing.assert_array_equal(first.right, recording.images(0)[1])
    assert first.time == pytest.approx(recording.times[0])


def test_recording_needs_a_run_folder(tmp_path: Path) -> None:
    path = tmp_path / "m.yaml"
    path.write_text(MISSION, encoding="utf-8")
    with pytest.raises(AuvError, match="needs a run folder"):
        simulate(load_mission(path), record_stereo=True)


def test_an_elements_recording_places_a_tilted_camera_by_its_mount(tmp_path: Path) -> None:
    from mission.language.mount import Mount
    from mission.plugin_api import StereoImages
    from mission.reconstruct import read_recording
    from mission.stereo_recording import ElementStereo
    from mission.vehicle import NavState, Observation

    tilted = Mount(tilt_deg=30.0).R_body_cam()
    nav = NavState(1.0, 10.0, 20.0, 30.0, 45.0, 1.0, 5.0, 0.5, 100.0)
    grey = np.zeros((8, 12), np.uint8)
    images = StereoImages(1.0, grey, grey, np.array([[10.0, 0, 6], [0, 10.0, 4], [0, 0, 1]]), 0.25)
    recording = ElementStereo(tmp_path, "scan", tilted)
    recording.add(Observation(nav, stereo=(images,)))
    recording.close()
    pose = read_recording(tmp_path / "stereo" / "scan").poses[0]
    expected = camera_pose(10.0, 20.0, 30.0, 45.0, baseline=0.25, R_body_cam=tilted)
    assert np.allclose(pose, expected, atol=1e-6)
    looking_down = camera_pose(10.0, 20.0, 30.0, 45.0, baseline=0.25)
    assert not np.allclose(pose[:3, :3], looking_down[:3, :3], atol=0.1)  # 60° apart: the mount is not ignored
