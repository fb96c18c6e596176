"""The characteristic-point sets `auv reconstruct` proposes from what the stereo-referencing plug-in's own detector
finds on the object in the recording's close views (`detected_point_sets`)."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from mission.reconstruct import Recording

Array = NDArray[np.float64]


def detected_point_sets(recording: Recording, plane: Array, lo: Array, hi: Array, reach_m: float = 4.0,
                        min_height_m: float = 0.25, every: int = 2, max_range_m: float = 8.0) -> list[Any]:
    """Sets of points the stereo-referencing plug-in's detector finds on the object (world frame), or [] when
    fewer than 4: the views within `reach_m` (horizontally) of the box (lo, hi)'s centre, every `every`-th, through
    the plug-in's own front end (`stereo_cloud`: Harris corners, its feature budget and range), placed at the
    recording's poses; the points `min_height_m` above the seabed plane in the box that many views found again
    (`stable_points`), grouped by `group_sets`."""
    import cv2

    from perception_plugins.reconstruction.keypoints import group_sets, stable_points
    from perception_plugins.referencing.plugin import MAX_FEATURES  # the proposed sets hold what it will detect
    from perception_plugins.stereo import RectifiedStereo, stereo_cloud

    first = cv2.imread(str(recording.left[0]), cv2.IMREAD_GRAYSCALE)
    if first is None:
        return []
    geometry = RectifiedStereo.from_K(recording.K, recording.baseline, (first.shape[1], first.shape[0]))
    centre = 0.5 * (lo + hi)
    clouds = []
    for k in range(0, len(recording.left), every):
        T = recording.poses[k]
        if np.linalg.norm(T[:2, 3] - centre) > reach_m:
            continue
        left = cv2.imread(str(recording.left[k]), cv2.IMREAD_GRAYSCALE)
        right = cv2.imread(str(recording.right[k]), cv2.IMREAD_GRAYSCALE)
        if left is None or right is None:
            continue
        pair = np.asarray(left, np.uint8), np.asarray(right, np.uint8)
        points = stereo_cloud(*pair, geometry, detector="harris", max_features=MAX_FEATURES,
                              max_range=max_range_m).points_cam
        world = points @ T[:3, :3].T + T[:3, 3]
        height = plane[0] * world[:, 0] + plane[1] * world[:, 1] + plane[2] - world[:, 2]
        inside = np.all((world[:, :2] >= lo - 0.2) & (world[:, :2] <= hi + 0.2), axis=1)
        clouds.append(world[(height > min_height_m) & inside])
    stable = stable_points(clouds)
    return group_sets(stable, 5, 2, 0.1) if len(stable) >= 4 else []


__all__ = ["detected_point_sets"]
