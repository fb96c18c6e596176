"""Corners looked for where the prior puts a set's characteristic points (seed 002 §3.3: the model guides the
detector), triangulated with the foreground's disparity.

Measured on the reference world's fine views (`benchmarks/set_diagnosis.py`): a skid fitting's top corner, a
low-contrast box on a fouled skid, has a Harris response of 10⁻⁴–10⁻¹ of the image's strongest (sand grains and
fouling), below the global detector's quality level or beyond its feature budget; and a characteristic point is
a top corner over lower ground, so three quarters of a window centred on it see the background: the descriptor
match fails or takes the background's disparity (module-top's lifting-point corner came out 0.6 m deep).

Here each predicted point gets its own search window (the prior's radius in pixels), whose own Harris maxima are
ranked by response times the prior's Gaussian, so texture elsewhere in the image takes nothing from it and a
strong corner at the window's edge ranks below a fainter one where the point is expected. Each corner's
disparity is found along its row within the range the prior allows, by normalised correlation of five windows:
centred and the four quadrants that have the corner at one of their corners (Fusiello's multiple windows). The
quadrant on the part's top sees only the part; of the windows that correlate well the one with the largest
disparity is kept, because a corner belongs to the nearest surface there. Pure numpy and OpenCV.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

HALF = 6  # quadrant window side - 1 (a quadrant is (HALF+1)² pixels), and the centred window's half side
MIN_NCC = 0.8  # a window whose correlation peak is below this does not measure the disparity
CLOSE_NCC = 0.05  # windows within this of the best peak are equally good; the largest disparity among them wins
PRIOR_SIGMA = 0.5  # the prior's Gaussian that ranks a window's corners, as a share of the prior radius
CORNERS_PER_POINT = 6  # Harris maxima kept per predicted point's window


@dataclass(frozen=True)
class GuidedCorners:
    """Triangulated guided corners in the left camera frame: (N, 3) points, their pixels and correlation."""

    points_cam: Array
    uv_left: Array
    score: Array


def _windows() -> list[tuple[NDArray[np.int_], NDArray[np.int_]]]:
    """(dy, dx) offsets of the centred window and of the four quadrants with the corner at a corner."""
    out = []
    dy, dx = np.mgrid[-HALF:HALF + 1, -HALF:HALF + 1]
    out.append((dy.ravel(), dx.ravel()))
    for sy in (-1, 1):
        for sx in (-1, 1):
            qy, qx = np.mgrid[0:HALF + 1, 0:HALF + 1]
            out.append(((sy * qy).ravel(), (sx * qx).ravel()))
    return out


WINDOWS = _windows()


def foreground_disparity(left: NDArray[np.uint8], right: NDArray[np.uint8], u: int, v: int, d_lo: float,
                         d_hi: float) -> tuple[float, float] | None:
    """Sub-pixel disparity of the left pixel (u, v) searched in [d_lo, d_hi], and its correlation: of the five
    windows whose peak correlates at least `MIN_NCC`, the largest disparity among those within `CLOSE_NCC` of the
    best. None when no window correlates or the search leaves the image."""
    h, w = left.shape[:2]
    lo, hi = int(np.floor(d_lo)) - 1, int(np.ceil(d_hi)) + 1
    if v - HALF < 0 or v + HALF >= h or u - HALF < 0 or u + HALF >= w or u - hi - HALF < 0 or u - lo + HALF >= w:
        return None
    shifts = np.arange(lo, hi + 1)
    found: list[tuple[float, float]] = []
    for dy, dx in WINDOWS:
        a = left[v + dy, u + dx].astype(np.float32)
        a = a - a.mean()
        b = right[(v + dy)[None, :], (u - shifts[:, None]) + dx[None, :]].astype(np.float32)
        b = b - b.mean(axis=1, keepdims=True)
        denom = float(np.sqrt((a * a).sum())) * np.sqrt((b * b).sum(axis=1))
        ncc = (b @ a) / np.maximum(denom, 1e-6)
        k = int(np.argmax(ncc[1:-1])) + 1
        c_minus, c0, c_plus = float(ncc[k - 1]), float(ncc[k]), float(ncc[k + 1])
        curvature = c_minus - 2.0 * c0 + c_plus
        if c0 < MIN_NCC or curvature >= 0:
            continue
        delta = 0.5 * (c_minus - c_plus) / curvature
        if abs(delta) > 1.0:
            continue
        found.append((float(shifts[k]) + delta, c0))
    if not found:
        return None
    best = max(c for _, c in found)
    return max((d, c) for d, c in found if c >= best - CLOSE_NCC)


def _window_corners(crop: NDArray[np.float32], centre: tuple[float, float], sigma_px: float) -> Array:
    """Up to `CORNERS_PER_POINT` Harris maxima of a window, ranked by response times the prior's Gaussian
    (σ = `sigma_px` around `centre`), refined to sub-pixel: a strong corner far from the prediction (sand along a
    skid's edge) ranks below a fainter one where the point is expected."""
    response = cv2.cornerHarris(crop, 5, 3, 0.04)
    peak = cv2.dilate(response, np.ones((2 * HALF + 1, 2 * HALF + 1), np.uint8))
    top = float(response.max())
    if top <= 0:
        return np.zeros((0, 2))
    ys, xs = np.nonzero((response >= peak) & (response >= 0.002 * top))
    inner = (xs >= HALF) & (xs < crop.shape[1] - HALF) & (ys >= HALF) & (ys < crop.shape[0] - HALF)
    ys, xs = ys[inner], xs[inner]
    if not len(xs):
        return np.zeros((0, 2))
    weight = response[ys, xs] * np.exp(-((xs - centre[0]) ** 2 + (ys - centre[1]) ** 2) / (2.0 * sigma_px ** 2))
    best = np.argsort(-weight)[:CORNERS_PER_POINT]
    seeds = np.column_stack([xs[best], ys[best]]).astype(np.float32).reshape(-1, 1, 2)
    refined = cv2.cornerSubPix(crop, seeds, (3, 3), (-1, -1),
                               (cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT, 20, 0.01))
    return np.asarray(refined, dtype=float).reshape(-1, 2)


def guided_corners(left: NDArray[np.uint8], right: NDArray[np.uint8], K: Array, baseline: float,
                   predicted_cam: Array, radius_m: float, depth_slack_m: float | None = None) -> GuidedCorners:
    """Corners near each predicted point (left camera frame, OpenCV axes) of a rectified pair: the best-ranked
    Harris maxima (`_window_corners`) within the prior's `radius_m` of its projection, triangulated with the
    foreground disparity within ± `depth_slack_m` (default `radius_m`) of its predicted depth."""
    fx, cx, cy = float(K[0, 0]), float(K[0, 2]), float(K[1, 2])
    fb = fx * baseline
    slack = radius_m if depth_slack_m is None else depth_slack_m
    h, w = left.shape[:2]
    pts: list[Array] = []
    uvs: list[tuple[float, float]] = []
    scores: list[float] = []
    seen: set[tuple[int, int]] = set()
    grey = np.asarray(left, dtype=np.float32)
    for p in np.asarray(predicted_cam, dtype=float):
        z = float(p[2])
        if z <= 0.3:
            continue
        u, v = fx * p[0] / z + cx, fx * p[1] / z + cy
        r = int(np.ceil(fx * radius_m / z)) + 2 * HALF
        x0, x1, y0, y1 = max(0, int(u) - r), min(w, int(u) + r + 1), max(0, int(v) - r), min(h, int(v) + r + 1)
        if x1 - x0 < 4 * HALF or y1 - y0 < 4 * HALF:
            continue
        crop = np.ascontiguousarray(grey[y0:y1, x0:x1])
        corners = _window_corners(crop, (u - x0, v - y0), PRIOR_SIGMA * fx * radius_m / z)
        if not len(corners):
            continue
        d_lo, d_hi = fb / (z + slack), fb / max(z - slack, 0.3)
        for cu, cv_ in corners.reshape(-1, 2):
            uu, vv = int(round(x0 + cu)), int(round(y0 + cv_))
            if (uu, vv) in seen:
                continue
            seen.add((uu, vv))
            found = foreground_disparity(left, right, uu, vv, d_lo, d_hi)
            if found is None:
                continue
            d, score = found
            zz = fb / d
            pts.append(np.array([(uu - cx) * zz / fx, (vv - cy) * zz / fx, zz]))
            uvs.append((float(uu), float(vv)))
            scores.append(score)
    if not pts:
        return GuidedCorners(np.zeros((0, 3)), np.zeros((0, 2)), np.zeros(0))
    return GuidedCorners(np.array(pts), np.array(uvs), np.array(scores))


__all__ = ["GuidedCorners", "foreground_disparity", "guided_corners"]
