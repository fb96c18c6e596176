"""The `replay` sensor driver: a recorded stereo folder in the KITTI odometry layout (what
`auv simulate --record-stereo` writes, or a KITTI sequence) played back as the `stereo` stream, paced by its
`times.txt` against the wall clock.

URI: `replay:FOLDER[?speed=S&loop=1]`. The folder holds `image_0/NNNNNN.png`, `image_1/NNNNNN.png` (8-bit grey,
rectified), `calib.txt` (`P0:` = K·[I|0], `P1:` whose 4th column is −fx·baseline) and `times.txt` (seconds, one
line per pair). Frame i goes out at `wall start + (t_i − t_0) / speed`, stamped with t_i (plus the recording's
length × the lap when looping); the next pair is read from disk while the current one waits for its time. Playback
runs while the sensor is requested on and pauses (its clock with it) while off. The requested frame rate thins
the stream: a frame goes out only when at least 1/rate of recorded time has passed since the last one.
"""

from __future__ import annotations

import threading
import time
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from mission.plugin_api import StereoImages
from mission.sensors import DriverContext, SensorError, split_query


def read_kitti_calibration(path: Path) -> tuple[NDArray[np.float64], float]:
    """K and the baseline (m) from a KITTI `calib.txt` (`P0:` and `P1:` rows of 12 numbers)."""
    rows: dict[str, NDArray[np.float64]] = {}
    try:
        for line in path.read_text(encoding="utf-8").splitlines():
            key, _, values = line.partition(":")
            if key.strip() in ("P0", "P1"):
                rows[key.strip()] = np.array([float(v) for v in values.split()], dtype=np.float64).reshape(3, 4)
    except (OSError, ValueError) as exc:
        raise SensorError(f"{path}: not a KITTI calibration: {exc}") from exc
    if set(rows) != {"P0", "P1"}:
        raise SensorError(f"{path}: needs P0: and P1: rows")
    P0, P1 = rows["P0"], rows["P1"]
    return P0[:, :3].copy(), float(-P1[0, 3] / P1[0, 0])


class ReplayDriver:
    """Plays a KITTI-layout stereo folder (see the module docstring)."""

    def __init__(self, address: str, context: DriverContext):
        path, query = split_query(address)
        self.folder = Path(path)
        if context.sensor != "stereo":
            raise SensorError(f"the replay driver plays stereo recordings, not the '{context.sensor}' stream")
        try:
            self.speed = float(query.get("speed", "1"))
        except ValueError as exc:
            raise SensorError(f"replay speed '{query.get('speed')}' is not a number") from exc
        if self.speed <= 0:
            raise SensorError("replay speed must be positive")
        self.loop = query.get("loop", "0") not in ("0", "", "false")
        self.K, self.baseline = read_kitti_calibration(self.folder / "calib.txt")
        try:
            self.times = np.atleast_1d(np.loadtxt(self.folder / "times.txt", ndmin=1))
        except (OSError, ValueError) as exc:
            raise SensorError(f"{self.folder}: no readable times.txt: {exc}") from exc
        self.left = sorted((self.folder / "image_0").glob("*.png"))
        self.right = sorted((self.folder / "image_1").glob("*.png"))
        if not (len(self.left) == len(self.right) == len(self.times) > 0):
            raise SensorError(f"{self.folder}: {len(self.left)} left, {len(self.right)} right images and "
                              f"{len(self.times)} times: they must agree")
        self.context = context
        self.sent = 0
        self._on = threading.Event()
        self._stop = threading.Event()
        self._min_gap = 0.0
        self._thread = threading.Thread(target=self._play, name="replay-stereo", daemon=True)
        self._thread.start()

    def _read(self, i: int) -> tuple[NDArray[np.uint8], NDArray[np.uint8]]:
        import cv2

        left = cv2.imread(str(self.left[i]), cv2.IMREAD_GRAYSCALE)
        right = cv2.imread(str(self.right[i]), cv2.IMREAD_GRAYSCALE)
        if left is None or right is None:
            raise SensorError(f"{self.folder}: cannot read the images of frame {i}")
        return np.asarray(left, dtype=np.uint8), np.asarray(right, dtype=np.uint8)

    def _play(self) -> None:
        n, t0 = len(self.times), float(self.times[0])
        lap_length = float(self.times[-1] - t0) + (float(np.median(np.diff(self.times))) if n > 1 else 0.0)
        k, last_sent = 0, -np.inf
        clock: float | None = None  # wall time at which recorded time t0 (of lap 0) is due
        paused_at: float | None = None
        while not self._stop.is_set():
            if not self._on.is_set():
                paused_at = paused_at if paused_at is not None else time.monotonic()
                self._on.wait(0.1)
                continue
            now = time.monotonic()
            if clock is None:
                clock = now
            elif paused_at is not None:
                clock += now - paused_at  # the recording's clock stood still while the sensor was off
            paused_at = None
            lap, i = divmod(k, n)
            if lap > 0 and not self.loop:
                return
            stamp = float(self.times[i]) + lap * lap_length
            k += 1
            if stamp - last_sent < self._min_gap - 1e-9:
                continue
            left, right = self._read(i)
            due = clock + (stamp - t0) / self.speed
            while not self._stop.is_set() and time.monotonic() < due:
                self._stop.wait(min(due - time.monotonic(), 0.05))
            if self._stop.is_set():
                return
            self.context.sink(StereoImages(stamp, left, right, self.K, self.baseline))
            self.sent += 1
            last_sent = stamp

    def request(self, on: bool, rate_hz: float | None) -> None:
        self._min_gap = 1.0 / rate_hz if rate_hz else 0.0
        if on:
            self._on.set()
        else:
            self._on.clear()

    def close(self) -> None:
        self._stop.set()
        self._on.set()
        self._thread.join(2.0)


def open_driver(address: str, context: DriverContext) -> ReplayDriver:
    """The `auv.sensors` factory for the scheme `replay`."""
    return ReplayDriver(address, context)
