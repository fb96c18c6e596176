"""The camera poses `auv reconstruct` fuses at: the recording's navigation poses, or (the default) those poses held
together by stereo odometry (`perception_plugins.reconstruction.pose_graph`: the relative motions between
consecutive frames and between revisits, anchored to navigation with its σ).

Navigation poses carry the fast part of the navigation's error (a USBL fix moves the estimate by decimetres from
one frame to the next), and a surface fused at them is smeared and doubled; the anchored poses keep stereo's
millimetres between frames and navigation's place over the recording.
"""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Any

import numpy as np

from mission.reconstruct import ReconstructionError, Recording

POSE_SOURCES = ("anchored", "navigation")


def frame_times(recording: Recording) -> np.ndarray:
    """Seconds of each frame (`times.txt`), or the frame numbers when the recording has no times."""
    path = recording.folder / "times.txt"
    if not path.is_file():
        return np.arange(len(recording.poses), dtype=float)
    try:
        times = np.atleast_1d(np.loadtxt(path, ndmin=1))
    except (OSError, ValueError) as e:
        raise ReconstructionError(f"{path}: cannot read the times: {e}") from e
    if len(times) != len(recording.poses):
        raise ReconstructionError(f"{path}: {len(times)} time(s) for {len(recording.poses)} pose(s)")
    return np.asarray(times, dtype=float)


def anchored_recording(recording: Recording) -> tuple[Recording, dict[str, Any]]:
    """The recording with its poses anchored (module docstring), and a report of the graph: edges measured (chain
    and revisit), how far the poses moved from navigation's, seconds."""
    import cv2

    from mission.plugin_api import StereoImages
    from perception_plugins.reconstruction.motions import candidate_pairs, measure_motions
    from perception_plugins.reconstruction.pose_graph import anchor_poses

    times = frame_times(recording)

    def load(k: int) -> StereoImages:
        left = cv2.imread(str(recording.left[k]), cv2.IMREAD_GRAYSCALE)
        right = cv2.imread(str(recording.right[k]), cv2.IMREAD_GRAYSCALE)
        if left is None or right is None:
            raise ReconstructionError(f"cannot read {recording.left[k]} or {recording.right[k]}")
        return StereoImages(float(times[k]), np.asarray(left, np.uint8), np.asarray(right, np.uint8), recording.K,
                            recording.baseline)

    t0 = time.process_time()
    pairs = candidate_pairs(recording.poses, times)
    edges = measure_motions(load, recording.poses, times, pairs)
    t1 = time.process_time()
    poses = anchor_poses(recording.poses, edges)
    t2 = time.process_time()
    moved = np.linalg.norm(poses[:, :3, 3] - recording.poses[:, :3, 3], axis=1)
    chained = sum(1 for e in edges if e.j - e.i <= 2)
    report = {"edges": len(edges), "chain_edges": chained, "revisit_edges": len(edges) - chained,
              "pairs_tried": len(pairs), "moved_from_navigation_m": {"median": round(float(np.median(moved)), 4),
                                                                     "max": round(float(moved.max()), 4)},
              "seconds": {"motions": round(t1 - t0, 2), "graph": round(t2 - t1, 2)}}
    return replace(recording, poses=poses), report


__all__ = ["POSE_SOURCES", "anchored_recording", "frame_times"]
