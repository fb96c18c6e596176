"""The camera driver reads two OpenCV sources (here video files the test writes with cv2.VideoWriter), pairs their
frames by timestamp, and hands out pairs with the calibration from a file."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

import cv2
import numpy as np
import pytest

from mission.language.models import Stereo
from mission.plugin_api import StereoImages
from mission.sensors import DriverContext, SensorError, SensorFrame, open_driver

W, H = 160, 120


def video(path: Path, fps: float, frames: int, value: Callable[[int], int]) -> Path:
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"MJPG"), fps, (W, H), isColor=False)
    assert writer.isOpened()
    for i in range(frames):
        writer.write(np.full((H, W), value(i), np.uint8))
    writer.release()
    return path


def calibration(path: Path) -> Path:
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    fs.write("K", np.array([[200.0, 0, 80], [0, 200.0, 60], [0, 0, 1]]))
    fs.write("baseline", 0.12)
    fs.release()
    return path


class Pairs:
    def __init__(self) -> None:
        self.frames: list[StereoImages] = []
        self.wall: list[float] = []

    def __call__(self, frame: SensorFrame) -> None:
        assert isinstance(frame, StereoImages)
        self.frames.append(frame)
        self.wall.append(time.monotonic())


def run(address: str, seconds: float) -> tuple[Pairs, object]:
    pairs = Pairs()
    driver = open_driver(f"camera:{address}", DriverContext("stereo", Stereo(), pairs))
    driver.request(True, None)
    time.sleep(seconds)
    driver.close()
    return pairs, driver


def test_pairs_take_left_and_right_frames_of_the_same_time(tmp_path: Path) -> None:
    left = video(tmp_path / "left.avi", 10, 12, lambda i: 10 * i)
    right = video(tmp_path / "right.avi", 20, 24, lambda i: 5 * i + 2)  # twice the rate: every other one pairs
    calib = calibration(tmp_path / "stereo.yaml")
    pairs, driver = run(f"{left},{right}?calibration={calib}", 1.8)
    assert len(pairs.frames) >= 10
    for k, pair in enumerate(pairs.frames):
        assert pair.time == pytest.approx(0.1 * k, abs=1e-3)
        assert abs(int(pair.left.mean()) - 10 * k) <= 3  # left frame k
        assert abs(int(pair.right.mean()) - (10 * k + 2)) <= 3  # right frame 2k: the same instant
    assert pair.baseline == pytest.approx(0.12) and pair.K[0, 0] == 200.0
    assert np.median(np.diff(pairs.wall)) == pytest.approx(0.1, abs=0.03)  # a file plays at its own pace
    assert driver.unpaired >= 9  # type: ignore[attr-defined]  # the right frames between the left ones


def test_a_missing_calibration_or_source_is_one_clear_error(tmp_path: Path) -> None:
    left = video(tmp_path / "left.avi", 10, 2, lambda i: 0)
    with pytest.raises(SensorError, match="needs \\?calibration=FILE"):
        open_driver(f"camera:{left},{left}", DriverContext("stereo", Stereo(), lambda f: None))
    with pytest.raises(SensorError, match="cannot be opened"):
        open_driver(f"camera:{left},{tmp_path / 'nope.avi'}?calibration={calibration(tmp_path / 'c.yaml')}",
                    DriverContext("stereo", Stereo(), lambda f: None))
