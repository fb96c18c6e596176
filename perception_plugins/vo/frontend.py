"""What the odometer asks of a front end (the part that turns images into motion between positions).

A front end holds a keyframe (the start of the current fragment). `start` makes a frame the keyframe, `track`
estimates a new position relative to it without changing any state (so that the odometer can try a shorter step
when it fails), and `commit` accepts a tracked position, ending the fragment there or not; it returns the final
T_key_b, which may be refined at the fragment's end.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from mission.plugin_api import StereoImages
from perception_plugins.stereo import RectifiedStereo

Array = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class Step:
    """A tracked position: its pose in the keyframe, the number of features supporting it, front-end data."""

    T_key_b: Array
    count: int
    data: dict[str, Any] = field(default_factory=dict)


class Frontend(Protocol):
    key_points: Array
    """(N, 3) the keyframe's triangulated points in its camera frame (its view, for overlaps and the step)."""

    def start(self, frame: StereoImages, mask: NDArray[np.uint8] | None = None) -> int: ...

    def track(self, frame: StereoImages, T_key_pred: Array | None) -> Step | None: ...

    def commit(self, frame: StereoImages, step: Step, end: bool) -> Array: ...


def geometry_of(frame: StereoImages) -> RectifiedStereo:
    h, w = frame.left.shape[:2]
    return RectifiedStereo.from_K(frame.K, frame.baseline, (w, h))


def grey(image: NDArray[np.uint8]) -> NDArray[np.uint8]:
    if image.ndim == 2:
        return image
    import cv2

    return np.asarray(cv2.cvtColor(image, cv2.COLOR_RGB2GRAY), dtype=np.uint8)


__all__ = ["Frontend", "Step", "geometry_of", "grey"]
