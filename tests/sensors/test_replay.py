"""The replay driver plays a KITTI-layout stereo folder at its recorded pace against the wall clock, stamped with
its own times, and the pairs it delivers give `stereo-vo` the trajectory `auv vo` computes from the folder."""

from __future__ import annotations

import threading
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from mission.language.models import Stereo
from mission.plugin_api import OdometryRequest, StereoImages
from mission.sensors import DriverContext, SensorError, SensorFrame, open_driver

KITTI = next((p for p in (Path(__file__).resolve().parents[3] / "shared" / "data" / "kitti06_0-50",
                           Path("/work/shared/data/kitti06_0-50")) if p.exists()), Path("kitti06_0-50"))
needs_kitti = pytest.mark.skipif(not (KITTI / "calib.txt").exists(), reason="needs ../shared/data/kitti06_0-50")


class Arrivals:
    def __init__(self, expected: int) -> None:
        self.frames: list[tuple[float, StereoImages]] = []
        self.expected = expected
        self.done = threading.Event()

    def __call__(self, frame: SensorFrame) -> None:
        assert isinstance(frame, StereoImages)
        self.frames.append((time.monotonic(), frame))
        if len(self.frames) >= self.expected:
            self.done.set()


def folder(root: Path, times: list[float]) -> Path:
    for side in ("image_0", "image_1"):
        (root / side).mkdir(parents=True)
        for i in range(len(times)):
            cv2.imwrite(str(root / side / f"{i:06d}.png"), np.full((20, 30), 10 * i + (side == "image_1"), np.uint8))
    (root / "calib.txt").write_text("P0: 700 0 300 0 0 700 100 0 0 0 1 0\nP1: 700 0 300 -175 0 700 100 0 0 0 1 0\n")
    (root / "times.txt").write_text("".join(f"{t}\n" for t in times))
    return root


def test_replay_paces_frames_by_their_recorded_times_and_stamps_them_with_those_times(tmp_path: Path) -> None:
    times = [100.0, 100.1, 100.2, 100.5, 100.6]  # a 0.3 s gap in the recording
    sink = Arrivals(len(times))
    driver = open_driver(f"replay:{folder(tmp_path / 'rec', times)}", DriverContext("stereo", Stereo(), sink))
    time.sleep(0.3)
    assert sink.frames == []  # nothing until the sensor is requested on
    driver.request(True, None)
    assert sink.done.wait(5.0)
    driver.close()
    wall = np.array([w for w, _ in sink.frames])
    stamps = [f.time for _, f in sink.frames]
    assert stamps == times
    assert np.allclose(np.diff(wall), np.diff(times), atol=0.04)
    first = sink.frames[0][1]
    assert first.baseline == pytest.approx(0.25) and first.K[0, 0] == 700.0
    assert int(first.left[0, 0]) == 0 and int(first.right[0, 0]) == 1


def test_a_requested_frame_rate_thins_the_replay(tmp_path: Path) -> None:
    times = [round(0.1 * i, 3) for i in range(10)]
    sink = Arrivals(5)
    driver = open_driver(f"replay:{folder(tmp_path / 'rec', times)}?speed=4", DriverContext("stereo", Stereo(), sink))
    driver.request(True, 5.0)
    assert sink.done.wait(5.0)
    time.sleep(0.2)
    driver.close()
    assert [f.time for _, f in sink.frames] == [0.0, 0.2, 0.4, 0.6, 0.8]


def test_a_folder_whose_files_disagree_is_refused_with_the_counts(tmp_path: Path) -> None:
    root = folder(tmp_path / "rec", [0.0, 0.1, 0.2])
    (root / "times.txt").write_text("0.0\n0.1\n")
    with pytest.raises(SensorError, match="3 left, 3 right images and 2 times"):
        open_driver(f"replay:{root}", DriverContext("stereo", Stereo(), lambda f: None))


@needs_kitti
def test_the_kitti_clip_replays_at_10_hz_and_gives_stereo_vo_the_trajectory_of_auv_vo() -> None:
    from perception_plugins.vo import estimate_trajectory, read_kitti_sequence
    from perception_plugins.vo.plugin import StereoOdometryPlugin

    n = 20
    sink = Arrivals(n)
    driver = open_driver(f"replay:{KITTI}", DriverContext("stereo", Stereo(), sink))
    driver.request(True, None)
    assert sink.done.wait(10.0)
    driver.close()
    wall = np.array([w for w, _ in sink.frames[:n]])
    assert np.median(np.diff(wall)) == pytest.approx(0.1, abs=0.01)  # 10 Hz against the wall clock
    assert wall[-1] - wall[0] == pytest.approx(0.1 * (n - 1), abs=0.1)

    plugin = StereoOdometryPlugin()
    plugin.configure({"method": "adaptive"})
    replayed = {}
    for i, (_, frame) in enumerate(sink.frames[:n]):
        result = plugin.process(frame, OdometryRequest(set_origin=i == 0))
        if result.ok and result.T_origin_cam is not None:
            replayed[i] = result.T_origin_cam
    reference = estimate_trajectory(list(read_kitti_sequence(KITTI))[:n], method="adaptive")
    assert len(replayed) >= 5
    for i, T in replayed.items():
        assert np.linalg.norm(T[:3, 3] - reference[i][:3, 3]) < 0.01, i
