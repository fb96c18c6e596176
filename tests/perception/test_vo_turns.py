"""VO through a turn on a short rendered down-looking sequence (1 m/s, turning 60° at 20°/s, 10 Hz): long KLT
tracking holds its end point within 1 % of the path with and without the bundle adjustment, the adjustment lowers
the window's reprojection error, and a KLT fragment's start continues the previous fragment's tracks."""

from __future__ import annotations

import math
import os
import tempfile
from collections.abc import Iterator

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("MESA_SHADER_CACHE_DIR", tempfile.mkdtemp(prefix="mesa-cache-"))

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from mission.geometry import invert  # noqa: E402
from mission.plugin_api import StereoImages  # noqa: E402
from perception_plugins.vo import Odometer, run_odometer, settings_for  # noqa: E402
from perception_plugins.vo.klt import KltTracker  # noqa: E402
from perception_plugins.vo.se3 import fill_poses  # noqa: E402


@pytest.fixture(scope="module")
def turn() -> Iterator[tuple[list[StereoImages], np.ndarray]]:
    from mission.sim.camera import RenderError
    from mission.sim.stereo_sequence import SequenceRenderer, VehiclePath, seabed_world

    fps, count = 10.0, 36
    t = np.arange(count) / fps
    rate = np.where((t >= 0.3) & (t < 3.3), 20.0, 0.0)  # deg/s: straight, 60° of turn, straight
    heading = np.concatenate([[0.0], np.cumsum(rate[:-1]) / fps])
    hd = np.radians(heading)
    north = np.concatenate([[0.0], np.cumsum(np.cos(hd[:-1]) / fps)])
    east = np.concatenate([[0.0], np.cumsum(np.sin(hd[:-1]) / fps)])
    states = np.column_stack([north, east, np.full(count, 4.0), heading, np.zeros(count), np.zeros(count)])
    try:
        seq = SequenceRenderer(seabed_world(seed=5), VehiclePath(t, states))
    except RenderError as exc:
        pytest.skip(f"no off-screen OpenGL here: {exc}")
    frames = list(seq)
    seq.close()
    yield frames, np.stack([invert(seq.poses[0]) @ P for P in seq.poses])


def _drift_percent(odometer: Odometer, frames: list[StereoImages], gt: np.ndarray) -> float:
    count, estimates = run_odometer(frames, odometer)
    poses = fill_poses({e.index: e.T_origin_cam for e in estimates}, count)
    path = float(np.linalg.norm(np.diff(gt[:, :3, 3], axis=0), axis=1).sum())
    return 100.0 * float(np.linalg.norm(poses[-1, :3, 3] - gt[-1, :3, 3])) / path


def test_the_rendered_turn_turns_sixty_degrees(turn: tuple[list[StereoImages], np.ndarray]) -> None:
    _, gt = turn
    yaw = math.degrees(math.acos(float(np.clip(gt[-1][:3, :3].trace() - 1.0, -2.0, 2.0)) / 2.0))
    assert yaw == pytest.approx(60.0, abs=2.1)


def test_long_klt_holds_its_end_point_through_the_turn(turn: tuple[list[StereoImages], np.ndarray]) -> None:
    frames, gt = turn
    assert _drift_percent(Odometer(settings_for("klt")), frames, gt) < 1.0


def test_the_bundle_adjustment_holds_the_turn_and_lowers_the_reprojection_error(
        turn: tuple[list[StereoImages], np.ndarray]) -> None:
    frames, gt = turn
    odometer = Odometer(settings_for("klt", bundle_window=6))
    assert _drift_percent(odometer, frames, gt) < 1.0
    assert odometer.window is not None
    stats = odometer.window.stats
    assert stats.adjustments >= 4
    assert float(np.mean(stats.rms_after_px)) < 0.9 * float(np.mean(stats.rms_before_px))


def test_a_klt_fragment_start_continues_the_survivors_tracks(turn: tuple[list[StereoImages], np.ndarray]) -> None:
    frames, _ = turn
    tracker = KltTracker(carry=True)
    tracker.start(frames[0])
    step = tracker.track(frames[2], None)
    assert step is not None
    tracker.commit(frames[2], step, end=True)
    matches = tracker.key_matches()
    assert matches is not None and len(matches.index) > 100
    tracker.start(frames[2])
    carried = matches.uv_left[np.all(np.isfinite(matches.uv_right), axis=1)]
    key = tracker.key_features().uv_left
    # every survivor seen in both end images is a key feature at exactly its tracked pixel
    nearest = np.min(np.linalg.norm(key[None, :, :] - carried[:, None, :], axis=2), axis=1)
    assert len(carried) > 100 and float(nearest.max()) < 1e-9
