"""Range maps: dense depth from one rectified stereo pair (seed 003 "3D reconstruction", first stage: the
"range finder" that turns each view into a depth map on the image grid).

OpenCV's semi-global matcher (`cv2.StereoSGBM`, 3-way mode) gives a disparity per pixel; three rejections follow:
left–right consistency (SGBM's `disp12MaxDiff`: the right-to-left match, computed from the same cost volume, must
land within one pixel), speckles (`cv2.filterSpeckles`: connected disparity blobs smaller than `speckle_px`
pixels are dropped) and low texture (the local grey-level standard deviation over the matching window under
`min_texture` grey levels: there the matcher only interpolates). Depth is Z = f·B / d; its σ follows from the
disparity's, σ_Z = Z² / (f·B) · σ_d, with σ_d the matcher's sub-pixel error (a calibration constant) grown where
the texture is weak.

`scale` > 1 matches images shrunk by that factor (area averaging): the disparity search and the map shrink with
it; K is scaled to the small grid, so the depth map comes with the K that projects onto it.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]
Image = NDArray[np.uint8]


@dataclass(frozen=True)
class RangeSettings:
    """How range maps are matched and filtered; the defaults suit 1–8 m ranges with fx ~1000 and B ~0.25 m."""

    min_range_m: float = 1.5
    max_range_m: float = 8.0
    scale: int = 2
    """Match images shrunk by this whole factor (1: full resolution)."""
    block: int = 5
    """SGBM matching window (pixels of the matched images)."""
    uniqueness: int = 10
    speckle_px: int = 120
    """Smallest disparity blob kept (pixels at full resolution)."""
    speckle_range_px: float = 1.0
    """Disparity step (px) that splits blobs."""
    min_texture: float = 2.0
    """Smallest local grey-level standard deviation matched (0–255 levels)."""
    sigma_disparity_px: float = 0.3
    """Sub-pixel disparity error of the matcher at full resolution, with good texture."""


@dataclass(frozen=True, eq=False)
class RangeMap:
    """A depth map on the (possibly shrunk) left image grid: NaN where rejected."""

    depth: NDArray[np.float32]
    """(h, w) depth along the left camera's z (m); NaN where there is no valid match."""
    sigma: NDArray[np.float32]
    """(h, w) standard deviation of the depth (m); NaN where depth is."""
    K: Array
    """(3, 3) intrinsics of this grid."""
    image: NDArray[np.float32]
    """(h, w) left grey image on this grid (0–255), for colouring."""

    @property
    def valid(self) -> NDArray[np.bool_]:
        return np.asarray(np.isfinite(self.depth))


def scaled_intrinsics(K: Array, scale: int) -> Array:
    """K of images shrunk `scale` times by area averaging (pixel centres at integers).

    >>> scaled_intrinsics(np.array([[1000.0, 0, 599.5], [0, 1000.0, 449.5], [0, 0, 1]]), 2).tolist()
    [[500.0, 0.0, 299.5], [0.0, 500.0, 224.5], [0.0, 0.0, 1.0]]
    """
    S = np.array([[1.0 / scale, 0.0, 0.5 / scale - 0.5], [0.0, 1.0 / scale, 0.5 / scale - 0.5], [0.0, 0.0, 1.0]])
    return np.asarray(S @ np.asarray(K, dtype=float))


def _shrink(image: Image, scale: int) -> Image:
    if scale == 1:
        return image
    h, w = image.shape[0] // scale, image.shape[1] // scale
    return np.asarray(cv2.resize(image[:h * scale, :w * scale], (w, h), interpolation=cv2.INTER_AREA), dtype=np.uint8)


def local_std(image: NDArray[np.float32], window: int) -> NDArray[np.float32]:
    """Grey-level standard deviation over a window×window box around each pixel.

    >>> float(local_std(np.full((9, 9), 7.0, dtype=np.float32), 5).max())
    0.0
    """
    mean = cv2.boxFilter(image, cv2.CV_32F, (window, window))
    mean_sq = cv2.boxFilter(image * image, cv2.CV_32F, (window, window))
    return np.asarray(np.sqrt(np.maximum(mean_sq - mean * mean, 0.0)), dtype=np.float32)


def _matcher(settings: RangeSettings, fb: float) -> tuple[cv2.StereoSGBM, int]:
    """The SGBM matcher for disparities from 0 to that of `min_range` at focal×baseline `fb` (px·m): the search
    starts at 0, not at `max_range`'s disparity, so that surfaces beyond `max_range` match where they are (and are
    dropped by range) instead of matching falsely inside a shortened search."""
    lo = 0
    span = int(np.ceil((fb / settings.min_range_m - lo) / 16.0)) * 16
    b = settings.block
    matcher = cv2.StereoSGBM.create(minDisparity=lo, numDisparities=max(span, 16), blockSize=b, P1=8 * b * b,
                                    P2=32 * b * b, disp12MaxDiff=1, uniquenessRatio=settings.uniqueness,
                                    speckleWindowSize=0, speckleRange=0, preFilterCap=31,
                                    mode=cv2.StereoSGBM_MODE_SGBM_3WAY)
    return matcher, lo


def range_map(left: Image, right: Image, K: Array, baseline: float,
              settings: RangeSettings | None = None) -> RangeMap:
    """The depth map of a rectified pair (right camera at +baseline along the left camera's x), with its σ."""
    s = settings or RangeSettings()
    small_l, small_r = _shrink(np.asarray(left), s.scale), _shrink(np.asarray(right), s.scale)
    Ks = scaled_intrinsics(K, s.scale)
    fb = float(Ks[0, 0]) * baseline
    matcher, lo = _matcher(s, fb)
    raw = matcher.compute(small_l, small_r)  # int16, 16 × disparity; lo − 1 where invalid
    speckle = max(int(s.speckle_px / s.scale**2), 4)
    cv2.filterSpeckles(raw, int(lo - 1) * 16, speckle, int(round(16 * s.speckle_range_px / s.scale)))
    disparity = raw.astype(np.float32) / 16.0
    grey = small_l.astype(np.float32)
    texture = local_std(grey, s.block)
    ok = (raw > lo * 16) & (texture >= s.min_texture)
    depth = np.full(disparity.shape, np.nan, dtype=np.float32)
    depth[ok] = fb / disparity[ok]
    ok &= (depth >= s.min_range_m) & (depth <= s.max_range_m)
    depth[~ok] = np.nan
    # σ_d: the matcher's sub-pixel error in this grid's pixels, grown where texture is weak (√ of the signal ratio).
    sigma_d = (s.sigma_disparity_px / s.scale) * np.sqrt(np.maximum(4.0 * s.min_texture / np.maximum(texture, 1e-3),
                                                                    1.0))
    sigma = np.where(ok, depth * depth / fb * sigma_d, np.nan).astype(np.float32)
    return RangeMap(depth, sigma, Ks, grey)


def points_from_range(rmap: RangeMap, stride: int = 1) -> tuple[Array, Array]:
    """(N, 3) camera points of the valid pixels (every `stride`-th row and column) and their (N,) σ."""
    depth = rmap.depth[::stride, ::stride]
    v, u = np.nonzero(np.isfinite(depth))
    z = depth[v, u].astype(float)
    u_full, v_full = u * stride, v * stride
    K = rmap.K
    x = (u_full - K[0, 2]) / K[0, 0] * z
    y = (v_full - K[1, 2]) / K[1, 1] * z
    return np.column_stack([x, y, z]), rmap.sigma[::stride, ::stride][v, u].astype(float)


def incidence_cosines(rmap: RangeMap) -> NDArray[np.float32]:
    """(h, w) |cos| of the angle between each pixel's ray and the surface normal estimated from the depth map's
    central differences (1 head-on, 0 grazing); NaN where the depth or a neighbour is missing.

    With P = z·(x, y, 1), x = (u − cx)/fx and y = (v − cy)/fy, the normal is ∂P/∂u × ∂P/∂v, written out per
    component (float32) rather than through `np.cross` on stacked arrays.
    """
    K = rmap.K
    z = rmap.depth
    h, w = z.shape
    x = ((np.arange(w) - K[0, 2]) / K[0, 0]).astype(np.float32)[None, :]
    y = ((np.arange(h) - K[1, 2]) / K[1, 1]).astype(np.float32)[:, None]
    zu = np.full_like(z, np.nan)
    zv = np.full_like(z, np.nan)
    zu[:, 1:-1] = 0.5 * (z[:, 2:] - z[:, :-2])  # ∂z/∂u
    zv[1:-1] = 0.5 * (z[2:] - z[:-2])  # ∂z/∂v
    fx, fy = np.float32(1.0 / K[0, 0]), np.float32(1.0 / K[1, 1])
    # ∂P/∂u = (x·zu + z/fx, y·zu, zu), ∂P/∂v = (x·zv, y·zv + z/fy, zv)
    a = (x * zu + z * fx, y * zu, zu)
    b = (x * zv, y * zv + z * fy, zv)
    n = (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
    dot = np.abs(n[0] * x + n[1] * y + n[2])
    norm = np.sqrt(n[0] ** 2 + n[1] ** 2 + n[2] ** 2) * np.sqrt(x * x + y * y + 1.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.asarray(dot / norm, dtype=np.float32)


__all__ = ["RangeMap", "RangeSettings", "incidence_cosines", "local_std", "points_from_range", "range_map",
           "scaled_intrinsics"]
