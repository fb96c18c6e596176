"""Stereo recordings in the KITTI odometry layout (seed 003 works on such sequences): the writer, and the
recording of a route element's stereo pairs that its `record` and `model` actions ask for.

A recording folder holds `image_0/NNNNNN.png` and `image_1/NNNNNN.png` (8-bit grey, left and right), `calib.txt`
(`P0:` = K·[I|0], `P1:` = K·[I|(−baseline, 0, 0)]), `times.txt` (seconds on the vehicle's clock) and one
KITTI pose file per pose source (12 numbers a line: T_world_left row-major, camera to world, world = the mission's
local NED frame). Pairs are written as they arrive, never held in memory.

An element's recording (`ElementStereo`) lives in `RUN/stereo/ELEMENT_ID/` and has one pose file, `poses.txt`:
the left camera's pose from the navigation estimate of the tick the pair arrived with (agents act on the
estimate; the truth is not the executive's to know). It is written by the executive in `auv simulate` and in
`auv run` alike, from the frames the vehicle delivers.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import IO, Any

import numpy as np

from mission.errors import AuvError
from mission.frames import R_BODY_CAM, Array, camera_pose
from mission.plugin_api import StereoImages
from mission.vehicle import Observation


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
    """Writes stereo pairs with their poses to `folder` as they come: `pose_files` names the pose files, and
    `write` takes one pose per name, in that order (by default the true pose, `poses.txt`, and the navigation's,
    `nav.txt`, as `auv simulate --record-stereo` writes them).

    Use as a context manager, or call `close()`; every line is flushed as it is written, so a recording cut short
    by a crash is still readable up to its last complete frame.
    """

    def __init__(self, folder: str | Path, pose_files: Sequence[str] = ("poses", "nav")):
        self.folder = Path(folder)
        self.frames = 0
        self.pose_files = tuple(pose_files)
        self._K: Array | None = None
        self._baseline = 0.0
        try:
            for sub in ("image_0", "image_1"):
                (self.folder / sub).mkdir(parents=True, exist_ok=True)
            self._files: dict[str, IO[str]] = {
                name: (self.folder / f"{name}.txt").open("w", encoding="utf-8")
                for name in ("times", *self.pose_files)}
        except OSError as e:
            raise StereoRecordError(f"{self.folder}: cannot create the stereo recording: {e}") from e

    def write(self, images: StereoImages, *poses: Array) -> None:
        """Append one pair: its images, its time and its poses (one per pose file)."""
        import cv2

        if len(poses) != len(self.pose_files):
            raise StereoRecordError(f"expected {len(self.pose_files)} pose(s) ({', '.join(self.pose_files)}), "
                                    f"got {len(poses)}")
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
        entries = [("times", f"{images.time:.6e}\n")] + [(k, _pose_line(T)) for k, T in zip(self.pose_files, poses,
                                                                                               strict=True)]
        for key, line in entries:
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


RECORDING_ACTIONS = ("record", "model")  # the actions that record an element's stereo pairs


class ElementStereo:
    """The stereo recording of one route element (its `record` or `model` action): every pair the vehicle
    delivers while the element runs, with the estimated left-camera pose, in `root/stereo/ELEMENT_ID/`
    (`relpath`). Without a `root` (no run folder) it only counts the pairs."""

    def __init__(self, root: Path | None, element_id: str, R_body_cam: Array | None = None):
        self.relpath = f"stereo/{element_id}"
        self.R_body_cam = R_BODY_CAM if R_body_cam is None else np.asarray(R_body_cam, dtype=float)
        self.pairs = 0
        self._recorder = StereoRecorder(root / self.relpath, ("poses",)) if root is not None else None

    def add(self, observation: Observation) -> None:
        """Record the pairs of one tick at the tick's estimated pose (position, measured depth and heading) and the
        camera's mount (`R_body_cam`, looking down by default)."""
        nav = observation.nav
        for images in observation.stereo:
            T_world_left = camera_pose(nav.north, nav.east, nav.depth, nav.heading, baseline=float(images.baseline),
                                        R_body_cam=self.R_body_cam)
            if self._recorder is not None:
                self._recorder.write(images, T_world_left)
            self.pairs += 1

    def close(self) -> None:
        if self._recorder is not None:
            self._recorder.close()
