"""Feature detection for stereo matching: SIFT, ORB and Harris corners with descriptors.

Seeds 000 (§3.1, §3.2) and 002 (§3.1) detect and match points with the SURF detector. SURF is patented
("nonfree") and absent from every OpenCV wheel on PyPI (neither opencv-python-headless nor the contrib wheel
enable it), so it is not offered here: SIFT (free since its patent expired in 2020; a scale-space blob detector with
a float descriptor, the closest stand-in for SURF), ORB (FAST corners with binary BRIEF descriptors, an order of
magnitude faster) and Harris corners (`cv2.goodFeaturesToTrack` with `useHarrisDetector`; seed 000 §3.1 names
"corner points ... recognized using the Harris Corner Detector"; described here by ORB's binary descriptor, upright
since a rectified pair has no rotation between its views) stand in wherever the seeds say SURF.

Keypoint positions are sub-pixel for SIFT and Harris (`cv2.cornerSubPix`), whole pixels at the pyramid level for
ORB; `matching.refine_disparities` brings any of them to sub-pixel disparities.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import cv2
import numpy as np
from numpy.typing import NDArray

Detector = Literal["sift", "orb", "harris"]
DETECTORS: tuple[Detector, ...] = ("sift", "orb", "harris")


@dataclass(frozen=True, eq=False)
class Features:
    """Keypoints of one image and their descriptors, row for row."""

    xy: NDArray[np.float64]
    """(N, 2) pixel coordinates (u right, v down)."""
    descriptors: NDArray[np.float32] | NDArray[np.uint8]
    """(N, D): float32 for SIFT (L2), packed bits uint8 for ORB and Harris (Hamming)."""
    response: NDArray[np.float64]
    """(N,) detector response (larger is stronger)."""
    binary: bool
    """True when descriptors are compared by Hamming distance."""

    def __len__(self) -> int:
        return int(self.xy.shape[0])

    def subset(self, index: NDArray[np.int_]) -> Features:
        return Features(self.xy[index], self.descriptors[index], self.response[index], self.binary)


def _grey(image: NDArray[np.uint8]) -> NDArray[np.uint8]:
    if image.ndim == 3:
        code = cv2.COLOR_RGB2GRAY if image.shape[2] == 3 else cv2.COLOR_RGBA2GRAY
        return np.asarray(cv2.cvtColor(image, code), dtype=np.uint8)
    return np.ascontiguousarray(image, dtype=np.uint8)


def _pack(keypoints: tuple[cv2.KeyPoint, ...] | list[cv2.KeyPoint], descriptors: NDArray[np.generic] | None,
          binary: bool) -> Features:
    if descriptors is None or len(keypoints) == 0:
        empty = np.zeros((0, 32), np.uint8) if binary else np.zeros((0, 128), np.float32)
        return Features(np.zeros((0, 2)), empty, np.zeros(0), binary)
    xy = np.array([kp.pt for kp in keypoints], dtype=float).reshape(-1, 2)
    response = np.array([kp.response for kp in keypoints], dtype=float)
    return Features(xy, np.ascontiguousarray(descriptors), response, binary)


def detect(image: NDArray[np.uint8], detector: Detector = "sift", max_features: int = 2000,
           mask: NDArray[np.uint8] | None = None, **options: float) -> Features:
    """Detect and describe up to `max_features` keypoints in a grey (or RGB) image.

    `options` go to the OpenCV constructor (SIFT: contrastThreshold …; ORB: fastThreshold …) or, for Harris, to
    the detector: `quality` (goodFeaturesToTrack's qualityLevel, default 0.005), `min_distance` (px, default 5),
    `k` (Harris k, default 0.04), `block_size` (default 5).
    """
    grey = _grey(image)
    if detector == "sift":
        sift = cv2.SIFT_create(nfeatures=max_features, **options)  # type: ignore[attr-defined]
        kps, desc = sift.detectAndCompute(grey, mask)
        return _pack(kps, desc, binary=False)
    if detector == "orb":
        orb_options = {"scaleFactor": 1.2, "nlevels": 8, "fastThreshold": 10, **options}
        orb = cv2.ORB_create(nfeatures=max_features, **orb_options)  # type: ignore[attr-defined]
        kps, desc = orb.detectAndCompute(grey, mask)
        return _pack(kps, desc, binary=True)
    if detector == "harris":
        return _harris(grey, max_features, mask, float(options.get("quality", 0.005)),
                       float(options.get("min_distance", 5.0)), float(options.get("k", 0.04)),
                       int(options.get("block_size", 5)))
    raise ValueError(f"unknown detector {detector!r} (available: {', '.join(DETECTORS)}; SURF is patented and absent "
                     "from the OpenCV wheels)")


def _harris(grey: NDArray[np.uint8], max_features: int, mask: NDArray[np.uint8] | None, quality: float,
            min_distance: float, k: float, block_size: int) -> Features:
    corners = cv2.goodFeaturesToTrack(grey, max_features, quality, min_distance, mask=mask, blockSize=block_size,
                                      useHarrisDetector=True, k=k)
    if corners is None:
        return _pack([], None, binary=True)
    corners = cv2.cornerSubPix(grey, corners.astype(np.float32), (4, 4), (-1, -1),
                               (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 20, 0.01))
    # Upright descriptors (angle 0): a rectified pair has no rotation between its views.
    keypoints = [cv2.KeyPoint(float(x), float(y), 31.0, 0.0, float(len(corners) - i))
                 for i, (x, y) in enumerate(corners.reshape(-1, 2))]
    orb = cv2.ORB_create(edgeThreshold=16, patchSize=31)  # type: ignore[attr-defined]
    kept, desc = orb.compute(grey, keypoints)
    return _pack(kept, desc, binary=True)


__all__ = ["DETECTORS", "Detector", "Features", "detect"]
