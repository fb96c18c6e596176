"""Visibility of candidate views by ray-casting the scanner frustum through the voxel states (seed 002 §2.2.2:
"the set of rays the scanner would emit, and how many unknown voxels it would reveal").

Rays are optimistic about unknown space (they pass through it) and stop at the first occupied voxel or at the
scanner's range. For each view:

* `unknown` (the utility's f): distinct unknown voxels the rays pass before they stop;
* `occupied`: distinct known occupied voxels the rays stop on, the structure the view sees;
* `contour` (the utility's ct): those of them on the open contour of the known structure, next to a frontier
  voxel (`derived.contour_mask`): where the structure seen so far continues into unexplored space, the part a
  contour-following view keeps in sight (fully mapped structure no longer counts, so contour following moves
  on);
* `hit_fraction`: the share of rays that stop on known structure (what the overlap term is made of).

All rays of a chunk of views are marched at once: sample points at `step` (0.7 voxel by default) along every
ray, one gather from the flattened state grid, the first occupied sample per ray by `argmax`, and a per-view
distinct count with a scratch array (each voxel id marks the scratch with its position; a position that reads
itself back is the one write that survived, so there is exactly one per distinct voxel). `ray_voxels` of
`planners.occupancy` is exact but lists each beam's voxels unordered and per origin, so the first hit would need
a sort per view; the sampled march is what fits here (a ray can skip a voxel it only clips by less than `step`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from planners.nbv.grid import StateGrid
from planners.nbv.views import Scanner, Views

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]
UNKNOWN_CODE, OUTSIDE, OCCUPIED_CODE, CONTOUR = 1, 2, 4, 5
"""March codes: free 0, unknown 1, outside the grid 2, occupied 4, occupied on the contour 5."""
_MARCH = np.array([UNKNOWN_CODE, 0, OCCUPIED_CODE], dtype=np.int8)
"""State (−1, 0, 1) + 1 → march code."""


@dataclass(frozen=True)
class Visibility:
    """Per-view visibility counts."""

    unknown: IntArray
    occupied: IntArray
    contour: IntArray
    hit_fraction: Array
    rays: int


def visibility(grid: StateGrid, views: Views, scanner: Scanner, step: float | None = None,
               chunk_samples: int = 1_000_000, contour: ArrayLike | None = None) -> Visibility:
    """Ray-cast every view's frustum through `grid`; see the module docstring for what is counted.

    `contour` (flat ids into `grid.states`) saves recomputing `contour_voxels(grid)` when the caller has it.
    """
    n = len(views)
    res = grid.resolution
    step = 0.7 * res if step is None else float(step)
    k_steps = max(1, math.ceil(scanner.max_range / step))
    t = ((np.arange(k_steps, dtype=np.float32) + 0.5) * np.float32(step / res)).astype(np.float32)
    t[-1] = min(float(t[-1]), scanner.max_range / res * (1 - 1e-6))
    dirs = scanner.directions(views.heading_deg, views.pitch_deg).astype(np.float32)
    rays = dirs.shape[1]
    # March codes on a one-voxel border of OUTSIDE: samples past it are clipped onto it, no masks needed; occupied
    # and contour codes are the only ones ≥ OCCUPIED_CODE, so "stops the ray" is one comparison.
    codes = np.full(tuple(n + 2 for n in grid.shape), OUTSIDE, dtype=np.int8)
    codes[1:-1, 1:-1, 1:-1] = _MARCH[grid.states + 1]
    edge_ids = contour_voxels(grid) if contour is None else np.asarray(contour, dtype=np.int64)
    codes[tuple(np.stack(np.unravel_index(edge_ids, grid.shape)) + 1)] = CONTOUR
    flat_codes = codes.reshape(-1)
    scratch = np.zeros(flat_codes.size, dtype=np.int32)
    origin_v = ((views.positions - grid.origin) / res + 1.0).astype(np.float32)
    unknown = np.zeros(n, dtype=np.int64)
    occupied = np.zeros(n, dtype=np.int64)
    contour_seen = np.zeros(n, dtype=np.int64)
    hits = np.zeros(n)
    per_chunk = max(1, chunk_samples // (rays * k_steps))
    steps = np.arange(k_steps, dtype=np.int32)[None, None, :]
    for c0 in range(0, n, per_chunk):
        c1 = min(n, c0 + per_chunk)
        flat = _sample_ids(origin_v[c0:c1], dirs[c0:c1], t, codes.shape)
        s = flat_codes[flat]
        occ = s >= OCCUPIED_CODE
        first = occ.argmax(axis=2).astype(np.int32)
        hit = np.take_along_axis(occ, first[:, :, None], axis=2)[:, :, 0]
        first[~hit] = k_steps
        unk = s == UNKNOWN_CODE
        unk &= steps < first[:, :, None]
        unk[:, :, 1:] &= flat[:, :, 1:] != flat[:, :, :-1]  # the same voxel sampled twice in a row counts once
        unknown[c0:c1] = _distinct_per_group(flat[unk], unk.sum(axis=(1, 2)), scratch)  # C order: view by view
        end_ids = np.take_along_axis(flat, np.minimum(first, k_steps - 1)[:, :, None], axis=2)[:, :, 0]
        occupied[c0:c1] = _distinct_per_group(end_ids[hit], hit.sum(axis=1), scratch)
        edge = hit & (flat_codes[end_ids] == CONTOUR)
        contour_seen[c0:c1] = _distinct_per_group(end_ids[edge], edge.sum(axis=1), scratch)
        hits[c0:c1] = hit.sum(axis=1) / rays
    return Visibility(unknown, occupied, contour_seen, hits, rays)


def contour_voxels(grid: StateGrid) -> IntArray:
    """Flat ids of the occupied voxels on the open contour of the known structure (`derived.contour_mask`)."""
    from planners.nbv.derived import contour_mask

    return np.flatnonzero(contour_mask(grid.states)).astype(np.int64)


def _sample_ids(origin_v: NDArray[np.float32], dirs: NDArray[np.float32], t: NDArray[np.float32],
                shape: tuple[int, ...]) -> NDArray[np.int32]:
    """Flat ids (C, R, K) into the padded grid of the samples o + d·t (padded voxel units), clipped onto its
    border (non-negative after clipping, so truncation is the floor)."""
    flat: NDArray[np.int32] | None = None
    stride = 1
    for axis in (2, 1, 0):
        coord = origin_v[:, None, None, axis] + dirs[:, :, None, axis] * t[None, None, :]
        np.clip(coord, 0.0, np.float32(shape[axis] - 1), out=coord)
        idx = coord.astype(np.int32)
        if stride != 1:
            idx *= np.int32(stride)
        flat = idx if flat is None else flat + idx
        stride *= shape[axis]
    assert flat is not None
    return flat


def _distinct_per_group(ids: NDArray[np.integer[Any]], counts: NDArray[np.integer[Any]],
                        scratch: NDArray[np.int32]) -> IntArray:
    """Distinct values in each consecutive group of `ids` (group g has `counts[g]` entries)."""
    out = np.zeros(len(counts), dtype=np.int64)
    ends = np.cumsum(counts)
    start = 0
    for g, end in enumerate(ends):
        if end > start:
            part = ids[start:end]
            stamp = np.arange(end - start, dtype=np.int32)
            scratch[part] = stamp
            out[g] = int(np.count_nonzero(scratch[part] == stamp))
        start = int(end)
    return out
