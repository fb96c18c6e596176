"""Face-side correlation patches (seed 000 §3.1 step 3.2, §3.2.2): the rectangle of pixels beside an edge on the
side where its face lies, sampled at sub-pixel positions and compared by zero-mean normalised cross-correlation.

A patch is a grid of pixel positions (P, 2). `side_grid` lays it on one side of an end point (offset from the
edge by a pixel, pulled a few pixels into the segment so that it stays on the face near a vertex); `sample`
reads any grid bilinearly; `scan_row` slides a grid along the epipolar row of a rectified partner image and
returns the best disparity (parabolic sub-pixel peak) and its correlation; `search_2d` looks for the best shift
of a grid within a small radius.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]
Image = NDArray[np.uint8]

HALF_ALONG = 7       # px: half length of a patch along the edge
DEPTH_ACROSS = 12    # px: patch depth across the edge, on the face side
GAP = 2              # px: the patch starts this far from the edge line
INSET = 9            # px: the patch centre is pulled this far into the segment from its end point


def side_grid(end: Array, direction: Array, side: float, inset: float = INSET) -> Array:
    """(P, 2) pixels of the face-side patch at end point `end` of a segment whose unit 2D direction points
    from this end into the segment; `side` = +1 lays the patch along the left normal (−dy, dx), −1 the other."""
    t = np.asarray(direction, dtype=float) / np.linalg.norm(direction)
    n = side * np.array([-t[1], t[0]])
    along = np.arange(-HALF_ALONG, HALF_ALONG + 1, dtype=float)
    across = np.arange(GAP, GAP + DEPTH_ACROSS, dtype=float)
    a, c = np.meshgrid(along, across, indexing="ij")
    centre = np.asarray(end, dtype=float) + inset * t
    return np.asarray(centre + a.reshape(-1, 1) * t + c.reshape(-1, 1) * n)


def sample(image: Image, grid: Array) -> NDArray[np.float32]:
    """Bilinear samples of a grey image at the grid's pixels (any leading shape; last axis (u, v)); NaN outside."""
    g = np.asarray(grid, dtype=float)
    u, v = g[..., 0], g[..., 1]
    h, w = image.shape[:2]
    outside = (u < 0) | (u > w - 1) | (v < 0) | (v > h - 1)
    u, v = np.clip(u, 0, w - 1.001), np.clip(v, 0, h - 1.001)
    u0, v0 = np.floor(u).astype(np.intp), np.floor(v).astype(np.intp)
    fu, fv = u - u0, v - v0
    img = np.asarray(image)
    top = img[v0, u0] * (1 - fu) + img[v0, u0 + 1] * fu
    bottom = img[v0 + 1, u0] * (1 - fu) + img[v0 + 1, u0 + 1] * fu
    values = (top * (1 - fv) + bottom * fv).astype(np.float32)
    values[outside] = np.nan
    return np.asarray(values, dtype=np.float32)


def zncc(a: NDArray[np.float32], b: NDArray[np.float32]) -> NDArray[np.float64]:
    """Zero-mean normalised cross-correlation of `a` (P,) with each row of `b` (..., P); NaN rows give −1."""
    x = a - np.mean(a)
    y = b - np.mean(b, axis=-1, keepdims=True)
    den = np.sqrt(np.sum(x * x)) * np.sqrt(np.sum(y * y, axis=-1))
    out = np.sum(y * x, axis=-1) / np.maximum(den, 1e-6)
    out = np.where(np.isfinite(out) & (den > 1e-3), out, -1.0)
    return np.asarray(out, dtype=float)


def texture(values: NDArray[np.float32]) -> float:
    """Standard deviation of a patch (grey levels): a flat patch cannot be correlated."""
    return float(np.std(values)) if np.all(np.isfinite(values)) else 0.0


@dataclass(frozen=True)
class Peak:
    """The best shift and its correlation; `ok` when it is an interior peak above the threshold."""

    shift: float
    score: float
    ok: bool


def _parabola(c_minus: float, c0: float, c_plus: float) -> float:
    curvature = c_minus - 2.0 * c0 + c_plus
    return 0.5 * (c_minus - c_plus) / curvature if curvature < 0 else 0.0


def scan_row(left: Image, right: Image, grid: Array, d_min: float, d_max: float, min_score: float = 0.7,
             min_texture: float = 2.0) -> Peak:
    """Slide the left patch at `grid` along the rectified right image's rows (u_r = u_l − d) for disparities
    d in [d_min, d_max] (whole pixels, then a parabola) and return the best disparity."""
    ref = sample(left, grid)
    if texture(ref) < min_texture:
        return Peak(0.0, -1.0, False)
    ds = np.arange(np.floor(d_min) - 1, np.ceil(d_max) + 2)
    if len(ds) < 3:
        return Peak(0.0, -1.0, False)
    shifted = grid[None, :, :] - np.stack([ds, np.zeros_like(ds)], axis=1)[:, None, :]
    scores = zncc(ref, sample(right, shifted))
    k = int(np.argmax(scores[1:-1])) + 1
    delta = _parabola(float(scores[k - 1]), float(scores[k]), float(scores[k + 1]))
    # A clear peak: the correlation must drop away from it (a flat face correlates everywhere along its row).
    far = np.abs(ds - ds[k]) > 3
    distinct = not np.any(far) or float(scores[k]) - float(np.max(scores[far])) > 0.1
    ok = bool(scores[k] >= min_score and abs(delta) <= 1.0 and distinct)
    return Peak(float(ds[k] + delta), float(scores[k]), ok)


def search_2d(reference: NDArray[np.float32], image: Image, grid: Array, radius: int, min_score: float = 0.7
              ) -> tuple[Array, float, bool]:
    """The shift (du, dv) within ±`radius` px at which `image` sampled at grid + shift best correlates with the
    `reference` samples (sub-pixel by a parabola per axis); returns (shift, score, ok)."""
    r = np.arange(-radius - 1, radius + 2, dtype=float)
    du, dv = np.meshgrid(r, r, indexing="xy")
    shifts = np.stack([du.ravel(), dv.ravel()], axis=1)
    scores = zncc(reference, sample(image, grid[None, :, :] + shifts[:, None, :])).reshape(len(r), len(r))
    inner = scores[1:-1, 1:-1]
    iv, iu = np.unravel_index(int(np.argmax(inner)), inner.shape)
    iv, iu = iv + 1, iu + 1
    best = float(scores[iv, iu])
    su = r[iu] + _parabola(float(scores[iv, iu - 1]), best, float(scores[iv, iu + 1]))
    sv = r[iv] + _parabola(float(scores[iv - 1, iu]), best, float(scores[iv + 1, iu]))
    ok = best >= min_score and abs(su - r[iu]) <= 1.0 and abs(sv - r[iv]) <= 1.0
    return np.array([su, sv]), best, bool(ok)


__all__ = ["Peak", "sample", "scan_row", "search_2d", "side_grid", "texture", "zncc"]
