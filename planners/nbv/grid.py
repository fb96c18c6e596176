"""A dense window of voxel states over the exploration box, kept in step with a `VoxelMap` (seed 002 §2.2.2).

Visibility casts tens of thousands of rays per iteration; it reads voxel states from a dense int8 array (1
occupied, 0 free, −1 unknown, as `VoxelMap.state`) instead of the sparse map. After each scan only the voxels
that scan touched are re-read from the map: `planners.occupancy.ray_voxels` lists the voxels its beams passed
through, and the beam ends are added.

>>> from planners.occupancy import VoxelMap
>>> m = VoxelMap(1.0)
>>> g = StateGrid.over(m, lo=(0, 0, 0), hi=(4, 4, 4))
>>> m.insert_scan([0.5, 0.5, 0.5], [[3.5, 0.5, 0.5]])
>>> [b.tolist() for b in g.refresh(m, [0.5, 0.5, 0.5], [[3.5, 0.5, 0.5]])]   # the box of voxels re-read
[[0, 0, 0], [4, 1, 1]]
>>> g.states[:, 0, 0].tolist(), g.occupied_ids.tolist()
([0, 0, 0, 1], [48])
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from planners.occupancy import VoxelMap, ray_voxels

Array = NDArray[np.float64]
OCCUPIED, FREE, UNKNOWN = 1, 0, -1


@dataclass
class StateGrid:
    """Voxel states on a dense box; voxel (i, j, k) is the map voxel with key `key_lo + (i, j, k)`."""

    states: NDArray[np.int8]
    key_lo: NDArray[np.int64]
    resolution: float
    occupied_ids: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    """Sorted flat ids of the occupied voxels, kept up to date by `refresh`."""

    def __post_init__(self) -> None:
        self.occupied_ids = np.flatnonzero(self.states.reshape(-1) == OCCUPIED).astype(np.int64)

    @classmethod
    def over(cls, voxel_map: VoxelMap, lo: ArrayLike, hi: ArrayLike) -> StateGrid:
        """The map's states over the box [lo, hi] (metres, snapped outwards to voxels)."""
        res = voxel_map.resolution
        k_lo = np.floor(np.asarray(lo, dtype=float) / res).astype(np.int64)
        k_hi = np.ceil(np.asarray(hi, dtype=float) / res).astype(np.int64)
        shape = tuple(int(v) for v in np.maximum(k_hi - k_lo, 1))
        states = np.full(shape, UNKNOWN, dtype=np.int8)
        _copy_blocks(voxel_map, k_lo, states)
        return cls(states, k_lo, res)

    @property
    def shape(self) -> tuple[int, int, int]:
        s = self.states.shape
        return int(s[0]), int(s[1]), int(s[2])

    @property
    def origin(self) -> Array:
        """Corner (metres) of voxel (0, 0, 0)."""
        return np.asarray(self.key_lo * self.resolution, dtype=float)

    @property
    def upper(self) -> Array:
        return np.asarray((self.key_lo + np.asarray(self.shape)) * self.resolution, dtype=float)

    def index(self, points: ArrayLike) -> tuple[NDArray[np.int64], NDArray[np.bool_]]:
        """Grid indices (N, 3) of points and whether they lie in the box."""
        p = np.asarray(points, dtype=float).reshape(-1, 3)
        ijk = np.floor(p / self.resolution).astype(np.int64) - self.key_lo
        inside: NDArray[np.bool_] = np.asarray(((ijk >= 0) & (ijk < np.asarray(self.shape))).all(axis=1))
        return ijk, inside

    def state(self, points: ArrayLike) -> NDArray[np.int8]:
        """(N,) states at points; unknown outside the box."""
        ijk, inside = self.index(points)
        out = np.full(len(ijk), UNKNOWN, dtype=np.int8)
        i = ijk[inside]
        out[inside] = self.states[i[:, 0], i[:, 1], i[:, 2]]
        return out

    def centres(self, ijk: ArrayLike) -> Array:
        """Centres (N, 3) in metres of grid indices."""
        return np.asarray((np.asarray(ijk, dtype=float).reshape(-1, 3) + self.key_lo + 0.5) * self.resolution,
                          dtype=float)

    def occupied_centres(self) -> Array:
        return self.centres(np.stack(np.unravel_index(self.occupied_ids, self.shape), axis=1))

    def refresh(self, voxel_map: VoxelMap, origin: ArrayLike, endpoints: ArrayLike) -> tuple[
            NDArray[np.int64], NDArray[np.int64]] | None:
        """Re-read from the map the voxels a scan from `origin` to `endpoints` (N, 3) touched.

        Returns the index box [lo, hi) of the voxels re-read (None when the scan touched none in the grid).
        """
        e = np.asarray(endpoints, dtype=float).reshape(-1, 3)
        e = e[np.isfinite(e).all(axis=1)]
        if not len(e):
            return None
        _, passed = ray_voxels(origin, e, self.resolution)
        keys = np.concatenate([passed, np.floor(e / self.resolution).astype(np.int64)])
        ijk = keys - self.key_lo
        inside = ((ijk >= 0) & (ijk < np.asarray(self.shape))).all(axis=1)
        if not inside.any():
            return None
        ijk = ijk[inside]
        lo, hi = ijk.min(axis=0), ijk.max(axis=0) + 1
        box = tuple(int(v) for v in hi - lo)
        touched = np.zeros(box, dtype=bool)  # a mask over the scan's box beats a sort or a hash
        touched[tuple((ijk - lo).T)] = True
        ijk = np.argwhere(touched) + lo
        flat = np.ravel_multi_index(tuple(ijk.T), self.shape)
        view = self.states.reshape(-1)
        old = view[flat]
        new = voxel_map.state(self.centres(ijk))
        view[flat] = new
        lost = flat[(old == OCCUPIED) & (new != OCCUPIED)]
        gained = flat[(new == OCCUPIED) & (old != OCCUPIED)]
        if len(lost) or len(gained):
            self.occupied_ids = np.union1d(np.setdiff1d(self.occupied_ids, lost, assume_unique=True), gained)
        return lo, hi


def _copy_blocks(voxel_map: VoxelMap, k_lo: NDArray[np.int64], states: NDArray[np.int8]) -> None:
    """Fill `states` (the box of keys [k_lo, k_lo + shape)) from the map's allocated blocks only: a survey-sized
    map holds its voxels in dense blocks (`planners.occupancy.blocks`), and voxels outside them are unknown."""
    store = voxel_map.store
    b = store.block
    occupied_code = voxel_map.codec.occupied_code
    k_hi = k_lo + np.asarray(states.shape)
    starts = store.block_keys[: store.count] * b
    overlap = ((starts < k_hi) & (starts + b > k_lo)).all(axis=1)
    codes = store.used().reshape(-1, b, b, b)
    for i in np.flatnonzero(overlap):
        lo = np.maximum(starts[i], k_lo)
        hi = np.minimum(starts[i] + b, k_hi)
        c = codes[i][tuple(slice(int(a), int(z)) for a, z in zip(lo - starts[i], hi - starts[i], strict=True))]
        block_states = np.where(c >= occupied_code, OCCUPIED, FREE).astype(np.int8)
        block_states[c == 0] = UNKNOWN
        states[tuple(slice(int(a), int(z)) for a, z in zip(lo - k_lo, hi - k_lo, strict=True))] = block_states

