"""The adaptive step of seed 003 ("Адаптивная методика расчета траектории"), Fig. 3 and equation (1).

The footprint of the view on the seabed along the motion is H = 2·tan(α/2)·R (α the field of view along the
motion, R the mean range to the bottom); keeping P per cent of it in common allows a displacement
S = H·(1 − P/100). With the speed V = V_{i−1} and the acceleration A = (V_{i−1} − V_{i−2}) / T_pre of the previous
steps, the step time T solves A·T² + 2·V·T − S = 0 (the distance at the mean speed V + A·T/2):

- A = 0: T = S / V;
- A < 0 and D = V² + 2·A·S < 0 (the vehicle stops before covering S): T = −V / A;
- otherwise T = (−V + √D) / A;

and the step in frames is T·fps. (Equation (1) as printed omits a factor 2 on S: T = S / (V + A·T/2) gives
A·T² + 2·V·T − 2·S = 0, whose roots are the (−V ± √D)/A with D = V² + 2·A·S that the seed then uses; we follow
the kinematics and the seed's D and roots.) The step is then halved while fewer than a threshold of features support the
motion (down to one frame: `Odometer`), and features are detected only where the two positions' views overlap
(`common_view_mask`).

For a camera looking along the motion (the KITTI car) the seed adapts the method without saying how; here the
overlap of a displacement S at angle θ to the optical axis is taken as 1 − S·(|sin θ|/H + |cos θ|/R) (the lateral
shift of the footprint plus the shrinking of the view of a plane at range R), so S = (1 − P/100) /
(|sin θ|/H + |cos θ|/R): H(1 − P/100) for a down-looking camera moving sideways, R(1 − P/100) straight ahead.

>>> round(footprint(60.0, 4.0), 6), round(overlap_displacement(60.0, 4.0, 75.0), 6)
(4.618802, 1.154701)
>>> step_time(1.0, 0.5, 0.0), step_time(1.0, 0.5, -0.5), round(step_time(1.0, 0.5, 0.25), 6)
(2.0, 1.0, 1.464102)
"""

from __future__ import annotations

import math

import cv2
import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


def footprint(alpha_deg: float, altitude: float) -> float:
    """H = 2·tan(α/2)·R: the view's extent on the bottom along the motion."""
    return 2.0 * math.tan(math.radians(alpha_deg) / 2.0) * altitude


def overlap_displacement(alpha_deg: float, altitude: float, overlap_percent: float,
                         axial_fraction: float = 0.0) -> float:
    """S: the displacement that keeps `overlap_percent` of the view in common; `axial_fraction` = |cos θ| of the
    motion's angle to the optical axis (0 for a down-looking camera moving horizontally: S = H·(1 − P/100))."""
    c = min(max(abs(axial_fraction), 0.0), 1.0)
    s = math.sqrt(max(0.0, 1.0 - c * c))
    H = footprint(alpha_deg, altitude)
    return (1.0 - overlap_percent / 100.0) / (s / H + c / altitude)


def step_time(S: float, V: float, A: float) -> float:
    """T of A·T² + 2·V·T − S = 0 with the seed's special cases; inf when the vehicle is (and stays) at rest."""
    if abs(A) < 1e-12:
        return S / V if V > 0 else math.inf
    D = V * V + 2.0 * A * S
    if A < 0 and D < 0:
        return -V / A
    T = (-V + math.sqrt(max(D, 0.0))) / A
    return T if T > 0 else math.inf


def step_frames(T: float, fps: float, max_frames: int) -> int:
    """The step in frames: T·fps rounded down, within [1, max_frames].

    >>> step_frames(1.464102, 25.0, 64), step_frames(math.inf, 25.0, 64), step_frames(0.01, 25.0, 64)
    (36, 64, 1)
    """
    if not math.isfinite(T):
        return max_frames
    return int(min(max(math.floor(T * fps + 1e-9), 1), max_frames))


def field_of_view_along(K: Array, image_size: tuple[int, int], direction_cam: Array) -> tuple[float, float]:
    """(α in degrees along the image-plane direction of a motion, |cos θ| of the motion to the optical axis)."""
    d = np.asarray(direction_cam, dtype=float)
    n = float(np.linalg.norm(d))
    if n < 1e-12:
        return math.degrees(2.0 * math.atan(0.5 * image_size[1] / K[1, 1])), 0.0
    d = d / n
    lateral = d[:2]
    ln = float(np.linalg.norm(lateral))
    w, h = image_size
    if ln < 1e-9:
        half = 0.5 * min(w / K[0, 0], h / K[1, 1])
    else:
        ux, uy = abs(lateral[0]) / ln, abs(lateral[1]) / ln
        half = min(0.5 * w / K[0, 0] / ux if ux > 1e-9 else math.inf, 0.5 * h / K[1, 1] / uy if uy > 1e-9
                   else math.inf)
    return math.degrees(2.0 * math.atan(half)), abs(float(d[2]))


def common_view_mask(K: Array, image_size: tuple[int, int], T_a_b: Array, depth: float,
                     margin: float = 0.1) -> NDArray[np.uint8]:
    """A mask of camera a's image: the part that camera b (at T_a_b) also sees, for a scene at `depth` along a's
    axis (the seabed facing a down-looking camera), widened by `margin` of the image size for the uncertainty of
    the predicted motion. The whole image when b's view does not reach the plane in front of a."""
    w, h = image_size
    mw, mh = margin * w, margin * h
    corners = np.array([[-mw, -mh], [w - 1 + mw, -mh], [w - 1 + mw, h - 1 + mh], [-mw, h - 1 + mh]])
    rays_b = np.column_stack([(corners[:, 0] - K[0, 2]) / K[0, 0], (corners[:, 1] - K[1, 2]) / K[1, 1],
                              np.ones(4)])
    R, t = T_a_b[:3, :3], T_a_b[:3, 3]
    rays_a = rays_b @ R.T
    full = np.full((h, w), 255, np.uint8)
    if np.any(rays_a[:, 2] <= 1e-6):
        return full
    s = (depth - t[2]) / rays_a[:, 2]
    if np.any(s <= 0):
        return full
    p = t + s[:, None] * rays_a
    uv = np.column_stack([K[0, 0] * p[:, 0] / p[:, 2] + K[0, 2], K[1, 1] * p[:, 1] / p[:, 2] + K[1, 2]])
    mask = np.zeros((h, w), np.uint8)
    cv2.fillConvexPoly(mask, np.rint(uv).astype(np.int32), 255)
    return mask if mask.mean() > 0.05 * 255 else full


__all__ = ["common_view_mask", "field_of_view_along", "footprint", "overlap_displacement", "step_frames",
           "step_time"]
