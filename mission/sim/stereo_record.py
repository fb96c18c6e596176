"""Recording a simulated run's stereo stream in the KITTI odometry layout, so `auv vo` evaluates it as it does KITTI.

A recording folder holds `image_0/NNNNNN.png` and `image_1/NNNNNN.png` (8-bit grey, left and right), `calib.txt`
(`P0:` = K·[I|0], `P1:` = K·[I|(−baseline, 0, 0)], so its 4th column is −fx·baseline), `times.txt` (simulation
seconds), `poses.txt` (the true T_world_left of each pair, KITTI's 12 numbers, world = the mission's local NED
frame) and `nav.txt` (the left camera's pose as the navigation estimate gave it when the pair was taken).
Pairs are written as they are captured, never held in memory (`mission.stereo_recording.StereoRecorder`).

An element's `record`/`model` recording (`mission.stereo_recording.ElementStereo`) has the same layout with
`poses.txt` the *estimated* pose and no `nav.txt`; `read_stereo_recording` reads both.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from mission.frames import Array, camera_pose
from mission.stereo_recording import StereoRecorder, StereoRecordError, projection_matrices
from mission.trajectory_eval import read_trajectory

if TYPE_CHECKING:
    from mission.plugin_api import StereoImages
    from mission.sim.vehicle import SimulatedVehicle

__all__ = ["StereoRecordError", "StereoRecorder", "StereoRecording", "projection_matrices", "read_stereo_recording",
           "record_vehicle_stereo"]


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
    """Read a folder written by `StereoRecorder`, checking that every file has one entry per frame (a recording
    without `nav.txt`, an element's, has estimated poses in `poses.txt`: they serve as both)."""
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
    poses = read_trajectory(root / "poses.txt").poses
    nav = read_trajectory(root / "nav.txt").poses if (root / "nav.txt").exists() else poses
    counts = {"image_0": len(lefts), "image_1": len(rights), "times.txt": len(times), "poses.txt": len(poses),
              "nav.txt": len(nav)}
    if len(set(counts.values())) != 1:
        raise StereoRecordError(f"{root}: files disagree on the number of frames: {counts}")
    return StereoRecording(root, K, baseline, times, poses, nav, lefts, rights)

