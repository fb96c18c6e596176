"""Recording a simulated run's stereo stream in the KITTI odometry layout, so `auv vo` evaluates it as it does KITTI.

A recording folder holds `image_0/NNNNNN.png` and `image_1/NNNNNN.png` (8-bit grey, left and right), `calib.txt`
(`P0:` = K·[I|0], `P1:` = K·[I|(−baseline, 0, 0)], so its 4th column is −fx·baseline), `times.txt` (simulation
seconds), `poses.txt` (the true T_world_left of each pair, KITTI's 12 numbers, world = the mission's local NED
frame) and `nav.txt` (the left camera's pose as the navigation estimate gave it when the pair was taken).
Pairs are written as they are captured, never held in memory.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

import numpy as np

from mission.errors import AuvError
from mission.frames import Array, camera_pose
from mission.plugin_api import StereoImages
from mission.trajectory_eval import read_trajectory

if TYPE_CHECKING:
    from mission.sim.vehicle import SimulatedVehicle


class StereoRecordError(AuvError):
    """A stereo recording cannot be written or read back."""


def projection_matrices(K: Array, baseline: float) -> tuple[Array, Array]:
    """KITTI's rectified projections P0 = K·[I|0] (left) and P1 = K·[I|(−b, 0, 0)] (right).

    >>> P0, P1 = projection_matrices(np.diag([500.0, 500.0, 1.0]), 0.25)
    >>> float(P1[0, 3]), float(P0[0, 3])
    (-125.0, 0.0)
    """
    P0 = np.hstack([K, np.zeros((3, 1))])
    P1 = np.hstack([K, K @ np.array([[-baseline], [0.0], [0.0]])])
    return P0, P1


def _pose_line(T: Array) -> str:
    return " ".join(f"{x:.9e}" for x in np.asarray(T, dtype=float)[:3, :4].reshape(-1)) + "\n"


class StereoRecorder:
    """Writes stereo pairs with their true and estimated poses to `folder` as they come (see the module docstring).

    Use as a context manager, or call `close()`; every line is flushed as it is written, so a recording cut short
    by a crash is still readable up to its last complete frame.
    """

    def __init__(self, folder: str | Path):
        self.folder = Path(folder)
        self.frames = 0
        self._K: Array | None = None
        self._baseline = 0.0
        try:
            for sub in ("image_0", "image_1"):
                (self.folder / sub).mkdir(parents=True, exist_ok=True)
            self._files: dict[str, IO[str]] = {
                name: (self.folder / f"{name}.txt").open("w", encoding="utf-8") for name in ("times", "poses", "nav")
            }
        except OSError as e:
            raise StereoRecordError(f"{self.folder}: cannot create the stereo recording: {e}") from e

    def write(self, images: StereoImages, T_world_left_true: Array, T_world_left_nav: Array) -> None:
        """Append one pair: its images, time, true pose and navigation pose."""
        import cv2

        K = np.asarray(images.K, dtype=float)
        if self._K is None:
            self._K, self._baseline = K, float(images.baseline)
            P0, P1 = projection_matrices(K, self._baseline)
            lines = [f"P{i}: " + " ".join(f"{x:.12e}" for x in P.reshape(-1)) for i, P in enumerate((P0, P1))]
            (self.folder / "calib.txt").write_text("\n".join(lines) + "\n", encoding="utf-8")
        elif not np.allclose(K, self._K) or float(images.baseline) != self._baseline:
            raise StereoRecordError(f"{self.folder}: the camera's calibration changed during the recording")
        name = f"{self.frames:06d}.png"
        for sub, image in (("image_0", images.left), ("image_1", images.right)):
            grey = np.asarray(image)
            if grey.dtype != np.uint8 or grey.ndim != 2:
                raise StereoRecordError(f"expected 8-bit grey images, got {grey.dtype} {grey.shape}")
            if not cv2.imwrite(str(self.folder / sub / name), grey):
                raise StereoRecordError(f"{self.folder / sub / name}: cannot write the image")
        for key, line in (("times", f"{images.time:.6e}\n"), ("poses", _pose_line(T_world_left_true)),
                          ("nav", _pose_line(T_world_left_nav))):
            self._files[key].write(line)
            self._files[key].flush()
        self.frames += 1

    def close(self) -> None:
        for f in self._files.values():
            f.close()

    def __enter__(self) -> StereoRecorder:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def record_vehicle_stereo(vehicle: SimulatedVehicle, folder: str | Path) -> StereoRecorder:
    """Attach a recorder to the vehicle's frame sink: each captured pair is written with its true pose and the
    pose the navigation estimate gives (estimated position, measured depth and heading)."""
    recorder = StereoRecorder(folder)

    def sink(images: StereoImages, T_world_left: Array) -> None:
        nav = camera_pose(vehicle.filter.north, vehicle.filter.east, vehicle.depth_meas, vehicle.heading_meas,
                          baseline=float(images.baseline))
        recorder.write(images, T_world_left, nav)

    vehicle.frame_sink = sink
    return recorder


@dataclass(frozen=True, eq=False)
class StereoRecording:
    """A recording read back: calibration, times, true and navigation poses, and the image files."""

    folder: Path
    K: Array
    baseline: float
    times: Array
    poses: Array  # (N, 4, 4) true T_world_left
    nav_poses: Array  # (N, 4, 4) T_world_left from the navigation estimate
    left_files: tuple[Path, ...]
    right_files: tuple[Path, ...]

    def __len__(self) -> int:
        return len(self.times)

    def images(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        """Left and right grey images of frame i."""
        import cv2

        pair = [cv2.imread(str(p), cv2.IMREAD_UNCHANGED) for p in (self.left_files[i], self.right_files[i])]
        if pair[0] is None or pair[1] is None:
            raise StereoRecordError(f"{self.folder}: cannot read the images of frame {i}")
        return pair[0], pair[1]


def read_stereo_recording(folder: str | Path) -> StereoRecording:
    """Read a folder written by `StereoRecorder`, checking that every file has one entry per frame."""
    root = Path(folder)
    from perception_plugins.vo import VoError, read_calibration

    try:
        K, baseline = read_calibration(root / "calib.txt")
    except VoError as e:
        raise StereoRecordError(str(e)) from e
    try:
        times = np.atleast_1d(np.loadtxt(root / "times.txt", ndmin=1))
    except (OSError, ValueError) as e:
        raise StereoRecordError(f"{root}: not a stereo recording: {e}") from e
    lefts = tuple(sorted((root / "image_0").glob("*.png")))
    rights = tuple(sorted((root / "image_1").glob("*.png")))
    poses, nav = read_trajectory(root / "poses.txt").poses, read_trajectory(root / "nav.txt").poses
    counts = {"image_0": len(lefts), "image_1": len(rights), "times.txt": len(times), "poses.txt": len(poses),
              "nav.txt": len(nav)}
    if len(set(counts.values())) != 1:
        raise StereoRecordError(f"{root}: files disagree on the number of frames: {counts}")
    return StereoRecording(root, K, baseline, times, poses, nav, lefts, rights)

