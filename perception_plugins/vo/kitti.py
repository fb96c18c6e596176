"""Stereo sequences in the KITTI odometry layout (Geiger, Lenz, Urtasun, CVPR 2012).

A sequence folder holds `image_0/NNNNNN.png` (left) and `image_1/NNNNNN.png` (right) rectified grey images,
`calib.txt` with the rectified 3×4 projections `P0:` and `P1:` (K = P0[:, :3], baseline = (P0[0,3] − P1[0,3]) /
P1[0,0]), optional `times.txt` (seconds, one per frame; 10 Hz assumed without it) and optional `poses.txt`
(ground truth: the 12 numbers of the row-major 3×4 [R|t] of the left camera in the first left-camera frame).
Images are read on demand, one pair per iteration step.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from mission.plugin_api import StereoImages
from perception_plugins.vo.errors import VoError


def read_calibration(path: str | Path) -> tuple[NDArray[np.float64], float]:
    """(K, baseline in m) from a KITTI `calib.txt`: K = P0[:, :3], baseline = (P0[0,3] − P1[0,3]) / P1[0,0].

    Lines without `:` are skipped; raises `VoError` (FILE[:LINE]: what is wrong) for an unreadable file, a line
    of non-numbers, a missing or short P0/P1, or a right camera that is not at a positive baseline.

    >>> import tempfile
    >>> f = Path(tempfile.mkdtemp()) / "calib.txt"
    >>> _ = f.write_text("P0: 500 0 320 0 0 500 240 0 0 0 1 0\\nP1: 500 0 320 -125 0 500 240 0 0 0 1 0\\n")
    >>> K, b = read_calibration(f)
    >>> float(K[0, 0]), b
    (500.0, 0.25)
    """
    path = Path(path)
    rows: dict[str, NDArray[np.float64]] = {}
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except OSError as exc:
        raise VoError(f"{path}: cannot read the calibration ({exc})") from exc
    for number, line in enumerate(lines, 1):
        if ":" not in line:
            continue
        key, values = line.split(":", 1)
        try:
            numbers = np.array([float(v) for v in values.split()])
        except ValueError as exc:
            raise VoError(f"{path}:{number}: expected numbers after '{key}:'") from exc
        rows[key.strip()] = numbers
    for key in ("P0", "P1"):
        if key not in rows or rows[key].size != 12:
            raise VoError(f"{path}: expected a line '{key}:' with the 12 numbers of a 3x4 projection matrix")
    P0, P1 = rows["P0"].reshape(3, 4), rows["P1"].reshape(3, 4)
    baseline = float((P0[0, 3] - P1[0, 3]) / P1[0, 0])
    if not baseline > 0:
        raise VoError(f"{path}: P1 must put the right camera at a positive baseline (got {baseline})")
    return np.asarray(P0[:, :3], dtype=float).copy(), baseline


def _read_rows(path: Path, width: int) -> NDArray[np.float64]:
    try:
        data = np.loadtxt(path, ndmin=2)
    except (OSError, ValueError) as exc:
        raise VoError(f"{path}: expected {width} numbers per line ({exc})") from exc
    if data.shape[1] != width:
        raise VoError(f"{path}: expected {width} numbers per line, found {data.shape[1]}")
    return np.asarray(data, dtype=float)


@dataclass(frozen=True, eq=False)
class KittiSequence:
    """A stereo sequence in the KITTI odometry layout; iterating yields `StereoImages`, reading images lazily."""

    path: Path
    left_files: tuple[Path, ...]
    right_files: tuple[Path, ...]
    times: NDArray[np.float64]
    K: NDArray[np.float64]
    baseline: float
    gt_poses: NDArray[np.float64] | None
    """(N, 4, 4) T_first_cam of the left camera, or None without poses.txt."""

    def __len__(self) -> int:
        return len(self.left_files)

    def __getitem__(self, i: int) -> StereoImages:
        left = cv2.imread(str(self.left_files[i]), cv2.IMREAD_GRAYSCALE)
        right = cv2.imread(str(self.right_files[i]), cv2.IMREAD_GRAYSCALE)
        if left is None or right is None:
            raise VoError(f"{self.path}: cannot read the image pair of frame {i}")
        return StereoImages(float(self.times[i]), np.asarray(left), np.asarray(right), self.K.copy(), self.baseline)

    def __iter__(self) -> Iterator[StereoImages]:
        for i in range(len(self)):
            yield self[i]


def read_kitti_sequence(path: str | Path) -> KittiSequence:
    """Open a sequence folder in the KITTI odometry layout (see the module docstring); raises `VoError` saying
    what is missing or malformed."""
    root = Path(path)
    if not root.is_dir():
        raise VoError(f"{root}: not a folder (expected a KITTI odometry sequence: image_0/, image_1/, calib.txt)")
    lefts = tuple(sorted((root / "image_0").glob("*.png")))
    rights = tuple(sorted((root / "image_1").glob("*.png")))
    if not lefts:
        raise VoError(f"{root}: no left images image_0/*.png")
    if [p.name for p in lefts] != [p.name for p in rights]:
        raise VoError(f"{root}: image_0/ and image_1/ must hold the same file names ({len(lefts)} left, "
                      f"{len(rights)} right)")
    K, baseline = read_calibration(root / "calib.txt")
    n = len(lefts)
    if (root / "times.txt").exists():
        times: NDArray[np.float64] = np.asarray(_read_rows(root / "times.txt", 1)[:, 0], dtype=np.float64)
        if len(times) != n:
            raise VoError(f"{root / 'times.txt'}: {len(times)} times for {n} frames")
    else:
        times = np.asarray(0.1 * np.arange(n), dtype=np.float64)
    gt = None
    if (root / "poses.txt").exists():
        rows = _read_rows(root / "poses.txt", 12)
        if len(rows) != n:
            raise VoError(f"{root / 'poses.txt'}: {len(rows)} poses for {n} frames")
        gt = np.tile(np.eye(4), (n, 1, 1))
        gt[:, :3, :] = rows.reshape(n, 3, 4)
    return KittiSequence(root, lefts, rights, times, K, baseline, gt)


__all__ = ["KittiSequence", "read_calibration", "read_kitti_sequence"]
