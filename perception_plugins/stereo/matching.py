"""Left–right matching of features on a rectified pair (seed 002 §3.1, seed 000 §3.2.1 step 3).

On a rectified pair a point's match lies on the same row, to its left: |v_l − v_r| ≤ `epipolar_tol` and
d = u_l − u_r in [d_min, d_max], where d_min comes from the stereo's maximum range and d_max from the nearest
range (`RectifiedStereo.disparity_range`). Only those epipolar candidates are compared, so the comparison is cheap
(a few candidates per feature instead of all of them) and a match that breaks the geometry cannot happen. Among a
feature's candidates the best must beat the second best by Lowe's `ratio` and, with `mutual`, be the best the
other way round too. `epipolar_inliers` applies the same geometric check to matches from any other matcher.

`refine_disparities` then brings each match to a sub-pixel disparity: zero-mean normalised cross-correlation of a
small window of the left image (at the left point rounded to whole pixels) with the right image at whole-pixel
shifts along the row, and a parabola through the peak and its neighbours.

>>> i, j = candidate_pairs(np.array([[100.0, 50.0]]), np.array([[60.0, 50.5], [90.0, 49.0], [30.0, 60.0]]),
...                        epipolar_tol=1.0, d_min=0.0, d_max=200.0)
>>> sorted(zip(i.tolist(), j.tolist()))  # (90, 49) and (60, 50.5) pass; (30, 60) is 10 rows off
[(0, 0), (0, 1)]
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from perception_plugins.stereo.features import Features

Array = NDArray[np.float64]
Index = NDArray[np.int_]

_POPCOUNT = np.array([bin(k).count("1") for k in range(256)], dtype=np.int32)


@dataclass(frozen=True, eq=False)
class StereoMatches:
    """Matched features, row for row: indices into the left and right `Features` and their pixels."""

    left: Index
    right: Index
    distance: Array
    """Descriptor distance (L2 for float descriptors, Hamming bits for binary)."""
    uv_left: Array
    uv_right: Array

    def __len__(self) -> int:
        return int(self.left.shape[0])

    @property
    def disparity(self) -> Array:
        return np.asarray(self.uv_left[:, 0] - self.uv_right[:, 0])

    def subset(self, keep: NDArray[np.bool_] | Index) -> StereoMatches:
        return StereoMatches(self.left[keep], self.right[keep], self.distance[keep], self.uv_left[keep],
                             self.uv_right[keep])


def epipolar_inliers(uv_left: Array, uv_right: Array, epipolar_tol: float, d_min: float = 0.0,
                     d_max: float = np.inf) -> NDArray[np.bool_]:
    """The epipolar check on a rectified pair: same row within `epipolar_tol` px, disparity in [d_min, d_max].

    >>> epipolar_inliers(np.array([[100.0, 50], [100, 50], [100, 50]]), np.array([[60.0, 51], [60, 55], [120, 50]]),
    ...                  2.0).tolist()
    [True, False, False]
    """
    uv_l, uv_r = np.asarray(uv_left, dtype=float), np.asarray(uv_right, dtype=float)
    d = uv_l[:, 0] - uv_r[:, 0]
    return np.asarray((np.abs(uv_l[:, 1] - uv_r[:, 1]) <= epipolar_tol) & (d >= d_min) & (d <= d_max))


def candidate_pairs(xy_left: Array, xy_right: Array, epipolar_tol: float, d_min: float,
                    d_max: float) -> tuple[Index, Index]:
    """All (left, right) index pairs that pass the epipolar check, found through the right points sorted by row."""
    order = np.argsort(xy_right[:, 1], kind="stable")
    rows = xy_right[order, 1]
    lo = np.searchsorted(rows, xy_left[:, 1] - epipolar_tol, side="left")
    hi = np.searchsorted(rows, xy_left[:, 1] + epipolar_tol, side="right")
    counts = hi - lo
    i = np.repeat(np.arange(len(xy_left)), counts)
    within = np.arange(int(counts.sum())) - np.repeat(np.cumsum(counts) - counts, counts)
    j = order[np.repeat(lo, counts) + within]
    d = xy_left[i, 0] - xy_right[j, 0]
    keep = (d >= d_min) & (d <= d_max)
    return i[keep], j[keep]


def descriptor_distances(left: Features, right: Features, i: Index, j: Index) -> Array:
    """Distances between the descriptors of left[i] and right[j], pair by pair."""
    if left.binary:
        return np.asarray(_POPCOUNT[np.bitwise_xor(left.descriptors[i], right.descriptors[j])].sum(axis=1), dtype=float)
    a = np.asarray(left.descriptors[i], dtype=np.float32)
    b = np.asarray(right.descriptors[j], dtype=np.float32)
    return np.asarray(np.sqrt(np.maximum(((a - b) ** 2).sum(axis=1), 0.0)), dtype=float)


def _best_two(group: Index, distance: Array) -> tuple[Index, Index, Array, Array]:
    """Per group: (group id, index of its best pair, best distance, second-best distance or inf)."""
    order = np.lexsort((distance, group))
    g, d = group[order], distance[order]
    start = np.flatnonzero(np.r_[True, g[1:] != g[:-1]]) if len(g) else np.zeros(0, dtype=int)
    nxt = np.minimum(start + 1, max(len(g) - 1, 0))
    has_second = (start + 1 < len(g)) & (g[nxt] == g[start]) if len(g) else np.zeros(0, dtype=bool)
    second = np.where(has_second, d[nxt] if len(g) else d, np.inf)
    return g[start], order[start], d[start], second


def match_stereo(left: Features, right: Features, epipolar_tol: float = 1.5, d_min: float = 0.0,
                 d_max: float = np.inf, ratio: float = 0.8, mutual: bool = True,
                 max_distance: float | None = None) -> StereoMatches:
    """Match features of a rectified pair among epipolar candidates, with the ratio test and the mutual check.

    A feature with a single candidate passes the ratio test (its second best is infinitely far); `max_distance`
    bounds the descriptor distance (default: none for SIFT, 64 bits of 256 for binary descriptors).
    """
    if max_distance is None and left.binary:
        max_distance = 64.0
    i, j = candidate_pairs(left.xy, right.xy, epipolar_tol, d_min, d_max)
    dist = descriptor_distances(left, right, i, j)
    _, best, best_d, second_d = _best_two(i, dist)
    keep = best_d < ratio * second_d
    if max_distance is not None:
        keep &= best_d <= max_distance
    chosen = best[keep]
    if mutual and len(chosen):
        _, best_for_right, _, _ = _best_two(j, dist)
        best_pair_of_right = np.full(len(right), -1)
        best_pair_of_right[j[best_for_right]] = best_for_right
        chosen = chosen[best_pair_of_right[j[chosen]] == chosen]
    li, rj = i[chosen], j[chosen]
    return StereoMatches(li, rj, dist[chosen], left.xy[li].copy(), right.xy[rj].copy())


def refine_disparities(left: NDArray[np.uint8], right: NDArray[np.uint8], uv_left: Array, uv_right: Array,
                       half: int = 4, search: int = 3, min_score: float = 0.6
                       ) -> tuple[Array, Array, Array, NDArray[np.bool_]]:
    """Sub-pixel disparities by correlation along the epipolar line.

    Returns (uv_left at whole pixels, uv_right on the same row with a sub-pixel column, correlation score, ok).
    A match is not ok when its window leaves the image, its correlation peak lies at the edge of the ±`search`
    range or is not a peak, or the score is below `min_score`; not-ok rows keep their input pixels.
    """
    uv_l, uv_r = np.asarray(uv_left, dtype=float), np.asarray(uv_right, dtype=float)
    h, w = left.shape[:2]
    u0 = np.rint(uv_l[:, 0]).astype(int)
    v0 = np.rint(uv_l[:, 1]).astype(int)
    x0 = np.rint(uv_r[:, 0] + (u0 - uv_l[:, 0])).astype(int)  # keep the disparity while rounding the left point
    reach = search + 1 + half
    inside = (u0 >= half) & (u0 < w - half) & (v0 >= half) & (v0 < h - half) & (x0 >= reach) & (x0 < w - reach)
    out_l, out_r = uv_l.copy(), uv_r.copy()
    score = np.full(len(uv_l), -1.0)
    idx = np.flatnonzero(inside)
    if len(idx) == 0:
        return out_l, out_r, score, inside
    dy, dx = (a.ravel() for a in np.mgrid[-half:half + 1, -half:half + 1])
    shifts = np.arange(-search - 1, search + 2)
    rows = v0[idx, None] + dy
    patch_l = left[rows, u0[idx, None] + dx].astype(np.float32)
    cols = x0[idx, None, None] + shifts[None, :, None] + dx[None, None, :]
    patch_r = right[rows[:, None, :], cols].astype(np.float32)
    a = patch_l - patch_l.mean(axis=1, keepdims=True)
    b = patch_r - patch_r.mean(axis=2, keepdims=True)
    denom = np.sqrt((a * a).sum(axis=1))[:, None] * np.sqrt((b * b).sum(axis=2))
    ncc = np.einsum("mp,msp->ms", a, b) / np.maximum(denom, 1e-6)
    k = 1 + np.argmax(ncc[:, 1:-1], axis=1)  # best inner shift; its neighbours exist
    m = np.arange(len(idx))
    c_minus, c0, c_plus = ncc[m, k - 1], ncc[m, k], ncc[m, k + 1]
    curvature = c_minus - 2.0 * c0 + c_plus
    delta = np.where(curvature < 0, 0.5 * (c_minus - c_plus) / np.where(curvature < 0, curvature, -1.0), 0.0)
    ok = (k > 1) & (k < len(shifts) - 2) & (curvature < 0) & (c0 >= min_score) & (np.abs(delta) <= 1.0)
    good = idx[ok]
    out_l[good, 0], out_l[good, 1] = u0[good], v0[good]
    out_r[good, 0] = x0[good] + shifts[k[ok]] + delta[ok]
    out_r[good, 1] = v0[good]
    score[idx] = c0
    valid = np.zeros(len(uv_l), dtype=bool)
    valid[good] = True
    return out_l, out_r, score, valid


__all__ = ["StereoMatches", "candidate_pairs", "descriptor_distances", "epipolar_inliers", "match_stereo",
           "refine_disparities"]
