"""Long KLT tracking over fragments (seed 003, "Длительное прослеживание особенностей", Fig. 1–2).

The feature set is generated at the fragment's start (the keyframe: spread corners, matched on the right image,
triangulated). At each step of the fragment the surviving features are tracked by pyramidal LK from the previous
position's image to the new one, seeded where the predicted motion puts them, and the new position's pose relative
to the keyframe comes from PnP-RANSAC on the keyframe's points (features failing it die). At the fragment's end
the survivors are tracked back from the end image to the start image: those that do not return within `back_tol`
pixels of where they started are dropped ("projection onto the start of the fragment", a filter of unreliable
tracks), the survivors are found in the end pair's right image, and the fragment's motion is re-estimated from them
on both end images (with a correction to the pair's disparity offset where the depths make it observable).

LK tracks across time on images low-passed by `track_blur_px` more than the stereo matching's: its sub-pixel
estimates lock toward whole pixels on sharp texture (`OdometerSettings.tracking_lowpass_px`).
"""

from __future__ import annotations

from dataclasses import replace

import cv2
import numpy as np
from numpy.typing import NDArray

from mission.geometry import invert, transform_points
from mission.plugin_api import StereoImages
from perception_plugins.stereo import RectifiedStereo, triangulate
from perception_plugins.vo.features import StereoFeatures, lk, stereo_features, stereo_match
from perception_plugins.vo.frontend import Array, Step, geometry_of, grey
from perception_plugins.vo.motion import estimate_motion
from perception_plugins.vo.window import KeyFeatures, Matches

OFFSET_DEPTH_RATIO = 2.5
"""A fragment estimates the disparity offset only when its points' depths span this ratio (90th over 10th
percentile; see `offset_observable`)."""


def offset_observable(depths: Array, ratio: float = OFFSET_DEPTH_RATIO) -> bool:
    """Whether points at these depths can tell a disparity offset δ from the translation's scale.

    δ moves a point's depth by the fraction δ/d of its disparity d. At one depth that is one scale factor for all
    the points, which the motion's translation absorbs; only points at very different disparities bend the scene
    in a way no scale explains. A down-looking camera over the seabed sees depths within a factor of 1.2–1.6 (the
    rendered Table-1 pass): there the fitted offsets follow whatever biases the tracks have (+0.08 px on average
    over 240 s against a true 0) and self-calibrating with them multiplied long KLT's error. A road scene spans a
    factor of 15–25 (KITTI 06), where the offset is observed.

    >>> offset_observable(np.array([5.0, 6.0, 7.0, 8.0])), offset_observable(np.geomspace(4.0, 60.0, 50))
    (False, True)
    """
    if len(depths) < 8:
        return False
    low, high = np.percentile(depths, [10.0, 90.0])
    return bool(high >= ratio * max(float(low), 1e-9))


def _project(K: Array, points: Array, shift: float = 0.0) -> Array:
    z = np.maximum(points[:, 2], 1e-6)
    return np.column_stack([K[0, 0] * (points[:, 0] - shift) / z + K[0, 2], K[1, 1] * points[:, 1] / z + K[1, 2]])


class KltTracker:
    """The long-tracking front end (see the module docstring)."""

    def __init__(self, features: int = 500, threshold_px: float = 1.5, back_tol: float = 1.0,
                 max_depth: float | None = None, calibrate_offset: bool = True,
                 offset_depth_ratio: float = OFFSET_DEPTH_RATIO, track_blur_px: float = 0.0,
                 carry: bool = False) -> None:
        self.features, self.threshold_px, self.back_tol, self.max_depth = features, threshold_px, back_tol, max_depth
        self.calibrate_offset, self.offset_depth_ratio = calibrate_offset, offset_depth_ratio
        self.track_blur_px = track_blur_px
        self.carry = carry
        """A fragment's start keeps the previous fragment's survivors (seen in both end images) as features at
        their tracked pixels, and detects new corners only away from them (`start`)."""
        self._carried: tuple[int, Array, Array] | None = None  # (id of the end frame, left pixels, right pixels)
        """σ (px) of the Gaussian applied to the images LK tracks across time (not to the stereo matching)."""
        self.offsets: list[float] = []
        """Disparity offsets (px) estimated at fragment ends (absolute: the offset in use plus the correction)."""
        self.doffs = 0.0
        """The disparity offset in use: the median of `offsets` once there are three."""
        self.key_points: Array = np.zeros((0, 3))
        self._key_uv: Array = np.zeros((0, 2))
        self._key_uv_right: Array = np.zeros((0, 2))
        self._matches: Matches | None = None
        self._key_image: NDArray[np.uint8] | None = None
        self._last_image: NDArray[np.uint8] | None = None
        self._last_uv: Array = np.zeros((0, 2))
        self._alive: NDArray[np.bool_] = np.zeros(0, dtype=bool)
        self._disparity = 0.0
        self._key_doffs = 0.0

    @property
    def alive(self) -> int:
        return int(self._alive.sum())

    def start(self, frame: StereoImages, mask: NDArray[np.uint8] | None = None) -> int:
        left, right = grey(frame.left), grey(frame.right)
        geometry = self._geometry(frame)
        carried, self._carried = self._carried if self._carried and self._carried[0] == id(frame) else None, None
        if carried is not None:
            # Continue the survivors' tracks: their end pixels become key features; new corners fill the rest.
            kept = triangulate(geometry, carried[1], carried[2])
            free = np.full(left.shape[:2], 255, np.uint8) if mask is None else mask.copy()
            for u, v in kept.uv_left:
                cv2.circle(free, (int(round(u)), int(round(v))), 7, 0, -1)
            new = stereo_features(left, right, geometry, max(self.features - len(kept), 0), free, self._disparity,
                                  self.max_depth)
            feats = StereoFeatures(np.concatenate([kept.uv_left, new.uv_left]),
                                   np.concatenate([kept.uv_right, new.uv_right]),
                                   np.concatenate([kept.points_cam, new.points_cam]))
        else:
            feats = stereo_features(left, right, geometry, self.features, mask, self._disparity, self.max_depth)
        self._key_doffs = self.doffs
        if len(feats):
            self._disparity = float(np.median(feats.uv_left[:, 0] - feats.uv_right[:, 0]))
        self.key_points, self._key_uv, self._key_uv_right = feats.points_cam, feats.uv_left, feats.uv_right
        self._key_image = self._last_image = self._for_tracking(left)
        self._last_uv = feats.uv_left.copy()
        self._alive = np.ones(len(feats), dtype=bool)
        return len(feats)

    def track(self, frame: StereoImages, T_key_pred: Array | None) -> Step | None:
        if self._last_image is None:
            return None
        idx = np.flatnonzero(self._alive)
        guess = None
        if T_key_pred is not None and len(idx):
            p = transform_points(invert(T_key_pred), self.key_points[idx])
            guess = np.where((p[:, 2] > 1e-3)[:, None], _project(frame.K, p), self._last_uv[idx])
        left = grey(frame.left)
        tracked = self._for_tracking(left)
        uv, ok = lk(self._last_image, tracked, self._last_uv[idx], guess)
        idx, uv = idx[ok], uv[ok]
        motion = estimate_motion(self.key_points[idx], uv, frame.K, T_a_b_guess=T_key_pred,
                                 threshold_px=self.threshold_px)
        if motion is None:
            return None
        return Step(motion.T_a_b, motion.count, {"index": idx[motion.inliers], "uv": uv[motion.inliers],
                                                 "left": left, "tracked": tracked})

    def key_features(self) -> KeyFeatures:
        return KeyFeatures(self._key_uv, self._key_uv_right, self.key_points)

    def key_matches(self) -> Matches | None:
        return self._matches

    def commit(self, frame: StereoImages, step: Step, end: bool) -> Array:
        idx, uv, left = step.data["index"], step.data["uv"], step.data["left"]
        self._matches = None
        self._alive[:] = False
        self._alive[idx] = True
        self._last_uv[idx] = uv
        self._last_image = step.data["tracked"]
        if not end or self._key_image is None:
            return step.T_key_b
        # Projection onto the fragment's start: the survivors must track back to where they were generated.
        back, ok = lk(self._last_image, self._key_image, uv, self._key_uv[idx])
        ok &= np.linalg.norm(back - self._key_uv[idx], axis=1) <= self.back_tol
        if ok.sum() < 8:
            ok[:] = True
        idx, uv = idx[ok], uv[ok]
        # Find the survivors in the end pair's right image, seeded by the motion's prediction, and re-estimate.
        p = transform_points(invert(step.T_key_b), self.key_points[idx])
        geometry = self._geometry(frame)
        disparity = geometry.fB / np.maximum(p[:, 2], 1e-3) - geometry.doffs
        uv_r, right_ok = stereo_match(left, grey(frame.right), uv, geometry, disparity)
        calibrate = self.calibrate_offset and offset_observable(self.key_points[idx, 2], self.offset_depth_ratio)
        motion = estimate_motion(self.key_points[idx], uv, frame.K, uv_b_right=uv_r, right_ok=right_ok,
                                 baseline=frame.baseline, T_a_b_guess=step.T_key_b, threshold_px=self.threshold_px,
                                 doffs=geometry.doffs, estimate_offset=calibrate)
        uv_r = np.where(right_ok[:, None], uv_r, np.nan)
        self._matches = Matches(idx, uv, uv_r)
        if motion is None:
            return step.T_key_b
        # The refinement must stay near the tracked estimate, and the offset correction small: on noise (a
        # sediment cloud) the joint fit can run off to a disparity near zero and an unbounded translation.
        moved = float(np.linalg.norm(motion.T_a_b[:3, 3] - step.T_key_b[:3, 3]))
        if abs(motion.disparity_offset) > 1.0 or moved > 0.2 * float(np.linalg.norm(step.T_key_b[:3, 3])) + 0.01:
            return step.T_key_b
        keep = motion.inliers
        self._matches = Matches(idx[keep], uv[keep], uv_r[keep])
        both = keep[right_ok[keep]]
        if self.carry:
            self._carried = (id(frame), uv[both], uv_r[both])
        if calibrate:
            self.offsets.append(self._key_doffs + motion.disparity_offset)
            if len(self.offsets) >= 3:
                self.doffs = float(np.median(self.offsets))
        return motion.T_a_b

    def _for_tracking(self, image: NDArray[np.uint8]) -> NDArray[np.uint8]:
        if self.track_blur_px <= 0.0:
            return image
        return np.asarray(cv2.GaussianBlur(image, (0, 0), self.track_blur_px, borderType=cv2.BORDER_REFLECT),
                          dtype=np.uint8)

    def _geometry(self, frame: StereoImages) -> RectifiedStereo:
        return replace(geometry_of(frame), doffs=geometry_of(frame).doffs + self.doffs)


__all__ = ["OFFSET_DEPTH_RATIO", "KltTracker", "offset_observable"]
