"""The `camera` sensor driver: two OpenCV `VideoCapture` sources (device indexes, stream URIs or video files) as
the `stereo` stream, paired in software by timestamp, with the calibration from a file.

URI: `camera:LEFT,RIGHT?calibration=FILE[&tolerance=S]` (e.g. `camera:0,1?calibration=stereo.yaml`), or
`camera:?left=rtsp://…&right=rtsp://…&calibration=FILE` when a source has a comma. Each source is read in its own
thread. A live source (a device or a stream) stamps a frame with the host's clock when it is grabbed; a video
file is played at its own frame rate against the wall clock and stamps a frame with its position in the file
(`CAP_PROP_POS_MSEC`), from the moment playback starts. A left frame is paired with the right frame nearest in
time within `tolerance` (default: a third of the left source's frame period); frames without a partner are
dropped and counted (`unpaired`). The pair's stamp is the left frame's.

Calibration: a KITTI `calib.txt` (`P0:`, `P1:` of rectified cameras), or an OpenCV FileStorage YAML/JSON with
either `K` (3×3) and `baseline` (m) for rectified sources, or `K1`, `D1`, `K2`, `D2`, `R`, `T` of a raw stereo rig
(then both images are rectified with `cv2.stereoRectify` and the baseline is |T|).
"""

from __future__ import annotations

import threading
import time
from collections import deque
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mission.plugin_api import StereoImages
from mission.sensors import DriverContext, SensorError, split_query
from mission.sensors.replay import read_kitti_calibration

Image = NDArray[np.uint8]


@dataclass(frozen=True)
class Calibration:
    """Rectified K and baseline, and the rectification maps of a raw rig (None when the sources are rectified)."""

    K: NDArray[np.float64]
    baseline: float
    maps: tuple[Any, Any, Any, Any] | None = None

    def rectify(self, left: Image, right: Image) -> tuple[Image, Image]:
        if self.maps is None:
            return left, right
        import cv2

        lx, ly, rx, ry = self.maps
        return (np.asarray(cv2.remap(left, lx, ly, cv2.INTER_LINEAR), dtype=np.uint8),
                np.asarray(cv2.remap(right, rx, ry, cv2.INTER_LINEAR), dtype=np.uint8))


def read_calibration(path: Path, image_size: tuple[int, int] | None = None) -> Calibration:
    """The stereo calibration in `path` (see the module docstring); `image_size` (w, h) is needed for a raw rig."""
    if path.suffix == ".txt":
        K, baseline = read_kitti_calibration(path)
        return Calibration(K, baseline)
    import cv2

    if not path.is_file():
        raise SensorError(f"{path}: no such calibration file")
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    try:
        def node(name: str) -> NDArray[np.float64] | None:
            n = fs.getNode(name)
            if n.empty():
                return None
            return np.asarray(n.real() if n.isReal() or n.isInt() else n.mat(), dtype=np.float64)

        k_node, b_node = node("K"), node("baseline")
        if k_node is not None and b_node is not None:
            return Calibration(k_node.reshape(3, 3), float(b_node.reshape(-1)[0]))
        raw = {n: node(n) for n in ("K1", "D1", "K2", "D2", "R", "T")}
    finally:
        fs.release()
    missing = [n for n, v in raw.items() if v is None]
    if missing:
        raise SensorError(f"{path}: needs K and baseline, or K1, D1, K2, D2, R, T (missing {', '.join(missing)})")
    if image_size is None:
        raise SensorError(f"{path}: a raw rig's calibration needs the image size")
    m: dict[str, Any] = raw
    R1, R2, P1, P2, *_ = cv2.stereoRectify(m["K1"], m["D1"], m["K2"], m["D2"], image_size, m["R"], m["T"], alpha=0)
    maps = (*cv2.initUndistortRectifyMap(m["K1"], m["D1"], R1, P1, image_size, cv2.CV_32FC1),
            *cv2.initUndistortRectifyMap(m["K2"], m["D2"], R2, P2, image_size, cv2.CV_32FC1))
    return Calibration(np.asarray(P1, dtype=np.float64)[:, :3].copy(), float(np.linalg.norm(m["T"])), maps)


def _source(spec: str) -> int | str:
    return int(spec) if spec.strip().isdigit() else spec


class _Reader:
    """One `VideoCapture` read in its own thread into a short deque of (stamp, grey image)."""

    def __init__(self, spec: str, name: str, on: threading.Event, stop: threading.Event,
                 arrived: threading.Condition):
        import cv2

        self.spec = _source(spec)
        self.cap = cv2.VideoCapture(self.spec)
        if not self.cap.isOpened():
            raise SensorError(f"camera source '{spec}' cannot be opened")
        self.is_file = isinstance(self.spec, str) and Path(self.spec).is_file()
        fps = float(self.cap.get(cv2.CAP_PROP_FPS) or 0.0)
        self.period = 1.0 / fps if fps > 0 else 0.1
        self.frames: deque[tuple[float, Image]] = deque(maxlen=8)
        self.ended = False
        self._on, self._stop, self._arrived = on, stop, arrived
        self._thread = threading.Thread(target=self._run, name=f"camera-{name}", daemon=True)

    def start(self, clock: list[float]) -> None:
        self._clock = clock
        self._thread.start()

    def _run(self) -> None:
        import cv2

        while not self._stop.is_set():
            if not self._on.wait(0.1):
                continue
            ok, image = self.cap.read()
            if not ok:
                self.ended = True
                with self._arrived:
                    self._arrived.notify_all()
                return
            if self.is_file:  # a file plays at its own pace: its position is the stamp
                stamp = float(self.cap.get(cv2.CAP_PROP_POS_MSEC)) / 1000.0
                due = self._clock[0] + stamp
                while not self._stop.is_set() and time.monotonic() < due:
                    self._stop.wait(min(due - time.monotonic(), 0.05))
            else:
                stamp = time.time()
            grey = image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
            with self._arrived:
                self.frames.append((stamp, np.asarray(grey, dtype=np.uint8)))
                self._arrived.notify_all()

    def close(self) -> None:
        if self._thread.is_alive():
            self._thread.join(2.0)
        self.cap.release()


class CameraDriver:
    """Two sources paired by timestamp (see the module docstring)."""

    def __init__(self, address: str, context: DriverContext):
        path, query = split_query(address)
        if context.sensor != "stereo":
            raise SensorError(f"the camera driver gives the stereo stream, not '{context.sensor}'")
        specs = [query["left"], query["right"]] if "left" in query and "right" in query else path.split(",")
        if len(specs) != 2 or not all(specs):
            raise SensorError(f"camera driver address '{address}' names two sources: LEFT,RIGHT")
        if "calibration" not in query:
            raise SensorError("the camera driver needs ?calibration=FILE")
        self.context = context
        self.unpaired = 0
        self.sent = 0
        self._on, self._stop, self._arrived = threading.Event(), threading.Event(), threading.Condition()
        self.readers = [_Reader(s, n, self._on, self._stop, self._arrived) for s, n in zip(specs, ("left", "right"),
                                                                                             strict=True)]
        import cv2

        size = (int(self.readers[0].cap.get(cv2.CAP_PROP_FRAME_WIDTH)),
                int(self.readers[0].cap.get(cv2.CAP_PROP_FRAME_HEIGHT)))
        self.calibration = read_calibration(Path(query["calibration"]), size)
        self.tolerance = float(query.get("tolerance", self.readers[0].period / 3.0))
        self._min_gap = 0.0
        self._clock = [0.0]
        self._started = False
        self._pairer = threading.Thread(target=self._pair, name="camera-pairing", daemon=True)

    def _pair(self) -> None:
        left, right = self.readers
        last = -np.inf
        while not self._stop.is_set():
            with self._arrived:
                self._arrived.wait(0.1)
                if not left.frames:
                    if left.ended:
                        return
                    continue
                t, image = left.frames[0]
                later = any(s > t + self.tolerance for s, _ in right.frames) or right.ended
                match = min(right.frames, key=lambda f: abs(f[0] - t), default=None)
                if match is None or abs(match[0] - t) > self.tolerance:
                    if later:  # no right frame will come close to this left one
                        left.frames.popleft()
                        self.unpaired += 1
                    continue
                left.frames.popleft()
                while right.frames and right.frames[0][0] <= match[0]:
                    dropped = right.frames.popleft()
                    self.unpaired += dropped is not match
            if t - last < self._min_gap - 1e-9:
                continue
            last = t
            a, b = self.calibration.rectify(image, match[1])
            self.context.sink(StereoImages(t, a, b, self.calibration.K, self.calibration.baseline))
            self.sent += 1

    def request(self, on: bool, rate_hz: float | None) -> None:
        self._min_gap = 1.0 / rate_hz if rate_hz else 0.0
        if on and not self._started:
            self._started = True
            self._clock[0] = time.monotonic()
            for r in self.readers:
                r.start(self._clock)
            self._pairer.start()
        if on:
            self._on.set()
        else:
            self._on.clear()

    def close(self) -> None:
        self._stop.set()
        self._on.set()
        if self._started:
            self._pairer.join(2.0)
        for r in self.readers:
            r.close()


def open_driver(address: str, context: DriverContext) -> CameraDriver:
    """The `auv.sensors` factory for the scheme `camera`."""
    return CameraDriver(address, context)
