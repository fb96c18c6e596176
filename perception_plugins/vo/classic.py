"""The classic two-position scheme of seed 003 ("Классическая вычислительная схема", Fig. 2).

Features are matched across the four images of two stereo pairs: each pair is matched along its rows
(`perception_plugins.stereo.stereo_cloud`: ORB keypoints standing in for SURF, epipolar candidates, ratio and
mutual checks, sub-pixel disparities, triangulation), then the left images of the two positions are matched by
descriptor (ratio and mutual checks), which keeps only the features seen in all four images. The motion follows
from the first pair's points and their pixels in the second pair (`motion.estimate_motion`: PnP-RANSAC, LM, both
images of the second pair). Every step is a fragment of its own: the chain gets one transform per step.
"""

from __future__ import annotations

import cv2
import numpy as np
from numpy.typing import NDArray

from mission.plugin_api import StereoImages
from perception_plugins.stereo import Cloud, Detector, stereo_cloud, triangulate
from perception_plugins.vo.features import stereo_match
from perception_plugins.vo.frontend import Array, Step, geometry_of, grey
from perception_plugins.vo.motion import estimate_motion
from perception_plugins.vo.window import KeyFeatures, Matches


def describe(frame: StereoImages, features: int = 1500, mask: NDArray[np.uint8] | None = None,
             detector: Detector = "harris") -> Cloud:
    """Stereo features of a pair with their triangulated points (left camera frame). Harris corners (sub-pixel,
    `cv2.cornerSubPix`) with ORB descriptors by default: the pixel positions feed the motion directly, and the
    whole-pixel positions of ORB keypoints (or of the correlation refinement, which rounds the left pixel) would
    quantise small steps. Disparities are refined by LK along the row (`features.stereo_match`)."""
    left, right = grey(frame.left), grey(frame.right)
    geometry = geometry_of(frame)
    cloud = stereo_cloud(left, right, geometry, detector, features, mask=mask, refine=False)
    # Sub-pixel disparities by LK along the row, seeded with the keypoints' own (as the KLT front end does), so
    # that the two schemes differ only in how they associate features across time.
    uv_r, ok = stereo_match(left, right, cloud.uv_left, geometry, cloud.disparity)
    refined = triangulate(geometry, cloud.uv_left[ok], uv_r[ok], descriptors=cloud.descriptors[ok])
    return refined


def match_descriptors(a: NDArray[np.generic], b: NDArray[np.generic], ratio: float = 0.8) -> tuple[NDArray[np.int_],
                                                                                               NDArray[np.int_]]:
    """Mutual best Hamming matches between two binary descriptor sets that pass the ratio test."""
    if len(a) < 2 or len(b) < 2:
        return np.zeros(0, dtype=int), np.zeros(0, dtype=int)
    matcher = cv2.BFMatcher(cv2.NORM_HAMMING)
    da, db = np.ascontiguousarray(a, dtype=np.uint8), np.ascontiguousarray(b, dtype=np.uint8)
    forward = matcher.knnMatch(da, db, k=2)
    backward = matcher.match(db, da)
    best_of_b = np.full(len(b), -1)
    for m in backward:
        best_of_b[m.queryIdx] = m.trainIdx
    ia, ib = [], []
    for pair in forward:
        if len(pair) == 2 and pair[0].distance < ratio * pair[1].distance and best_of_b[pair[0].trainIdx] == \
                pair[0].queryIdx:
            ia.append(pair[0].queryIdx)
            ib.append(pair[0].trainIdx)
    return np.asarray(ia, dtype=int), np.asarray(ib, dtype=int)


class ClassicMatcher:
    """The classic front end (see the module docstring)."""

    def __init__(self, features: int = 1500, threshold_px: float = 1.5) -> None:
        self.features, self.threshold_px = features, threshold_px
        self.key_points: Array = np.zeros((0, 3))
        self._key: Cloud | None = None
        self._pending: tuple[int, Cloud] | None = None
        self._matches: Matches | None = None

    def start(self, frame: StereoImages, mask: NDArray[np.uint8] | None = None) -> int:
        if self._pending is not None and self._pending[0] == id(frame) and mask is None:
            self._key = self._pending[1]
        else:
            self._key = describe(frame, self.features, mask)
        self._pending = None
        self.key_points = self._key.points_cam
        return len(self._key)

    def track(self, frame: StereoImages, T_key_pred: Array | None) -> Step | None:
        if self._key is None:
            return None
        cloud = describe(frame, self.features)
        ia, ib = match_descriptors(self._key.descriptors, cloud.descriptors)
        motion = estimate_motion(self._key.points_cam[ia], cloud.uv_left[ib], frame.K, uv_b_right=cloud.uv_right[ib],
                                 baseline=frame.baseline, T_a_b_guess=T_key_pred, threshold_px=self.threshold_px)
        if motion is None:
            return None
        a, b = ia[motion.inliers], ib[motion.inliers]
        return Step(motion.T_a_b, motion.count,
                    {"cloud": cloud, "matches": Matches(a, cloud.uv_left[b], cloud.uv_right[b])})

    def key_features(self) -> KeyFeatures:
        if self._key is None:
            return KeyFeatures(np.zeros((0, 2)), np.zeros((0, 2)), np.zeros((0, 3)))
        return KeyFeatures(self._key.uv_left, self._key.uv_right, self._key.points_cam)

    def key_matches(self) -> Matches | None:
        return self._matches

    def commit(self, frame: StereoImages, step: Step, end: bool) -> Array:
        self._pending = (id(frame), step.data["cloud"])
        self._matches = step.data["matches"]
        return step.T_key_b


__all__ = ["ClassicMatcher", "describe", "match_descriptors"]
