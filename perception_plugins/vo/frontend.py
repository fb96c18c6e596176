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
from perception_plugins.vo.window import KeyFeatures, Matches

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

    def key_features(self) -> KeyFeatures:
        """The keyframe's features: left and right pixels and the points (rows of `key_points`)."""
        ...

    def key_matches(self) -> Matches | None:
        """After a `commit` that ended a fragment: the keyframe's features found in the fragment's end pair."""
        ...

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


FLAT_FIELD_FLOOR = 1.0
"""Added to the local mean before dividing (grey levels), so that black areas (a lamp failure) divide by no zero.
It does not limit the gain in dim areas: there the flat field amplifies noise with the texture (measured on the
degraded mud run: KLT losses 9.6 → 16 %; floors of 20 and 60 gave 14 % and 12 %, not tried further)."""


def flat_field(image: NDArray[np.uint8], sigma_px: float) -> NDArray[np.uint8]:
    """The grey image divided by its own Gaussian blur (σ `sigma_px`), scaled to a mean near 120.

    A vehicle's lamp lights the seabed unevenly and moves with it, so a seabed point's brightness changes from frame
    to frame; Lucas–Kanade assumes it does not (brightness constancy), and the tracks drift with the light.
    Dividing by the local mean brightness leaves the texture and removes the shading (a flat-field correction).

    >>> shade = np.linspace(40, 200, 64)[None, :] * np.ones((64, 1))
    >>> texture = 1 + 0.2 * (np.indices((64, 64)).sum(0) % 2)
    >>> out = flat_field(np.clip(shade * texture, 0, 255).astype(np.uint8), 4.0)
    >>> bool(abs(float(out[:, 8:24].mean()) - float(out[:, 40:56].mean())) < 8)
    True
    """
    import cv2

    g = grey(image).astype(np.float32)
    h, w = g.shape
    # The blur is smooth: compute it on a 4× smaller image (16× fewer pixels) and scale it back up.
    k = 4 if sigma_px >= 8.0 and min(h, w) >= 64 else 1
    small = cv2.resize(g, (max(1, w // k), max(1, h // k)), interpolation=cv2.INTER_AREA) if k > 1 else g
    mean = cv2.GaussianBlur(small, (0, 0), sigma_px / k, borderType=cv2.BORDER_REFLECT)
    if k > 1:
        mean = cv2.resize(mean, (w, h), interpolation=cv2.INTER_LINEAR)
    return np.asarray(np.clip(np.rint(120.0 * g / (mean + FLAT_FIELD_FLOOR)), 0, 255), dtype=np.uint8)


def prepare(image: NDArray[np.uint8], flat_field_px: float | None, prefilter_px: float | None) -> NDArray[np.uint8]:
    """What the front ends see of an image: grey, flat-fielded (`flat_field`) unless `flat_field_px` is None, then
    smoothed by a Gaussian of σ `prefilter_px` unless that is None (a low-pass against sensor noise, which the
    flat field amplifies in dim areas, and against aliased texture, on which Lucas–Kanade's sub-pixel estimates
    lock toward whole pixels).

    >>> rng = np.random.default_rng(0)
    >>> noisy = np.clip(rng.normal(100, 10, (64, 64)), 0, 255).astype(np.uint8)
    >>> float(prepare(noisy, None, None).std()) > 9, float(prepare(noisy, None, 1.5).std()) < 4
    (True, True)
    """
    out = grey(image) if flat_field_px is None else flat_field(image, flat_field_px)
    if prefilter_px is None or prefilter_px <= 0.0:
        return out
    import cv2

    return np.asarray(cv2.GaussianBlur(out, (0, 0), prefilter_px, borderType=cv2.BORDER_REFLECT), dtype=np.uint8)


__all__ = ["Frontend", "Step", "flat_field", "geometry_of", "grey", "prepare"]
