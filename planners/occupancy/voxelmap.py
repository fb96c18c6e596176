"""The voxel occupancy map of seed 002 §2.1: multibeam pings fused by Bayes (log-odds) updates.

Every voxel starts unknown (probability 0.5, "full uncertainty" in the seed). Each ping updates the voxels its
beams pass through as free (a miss) and the voxel each beam ends in as occupied (a hit), at most once per ping
each; a voxel both passed and hit in the same ping counts as hit only (OctoMap's `insertPointCloud`, which
keeps a beam grazing the seabed from erasing its neighbours' returns). Beams without a return carve free space
only. World frame NED in metres; voxel k along an axis spans [k·resolution, (k+1)·resolution), as in OctoMap.

The update needs no loop over beams or voxels: `raycast.traverse` lists every (beam, voxel) pair of the ping,
`BlockStore` turns them into pool positions, and one gather–table–scatter applies the update. Repeated positions
are harmless: a fancy-indexed read-modify-write reads every copy before writing, so each voxel changes once.

>>> import numpy as np
>>> m = VoxelMap(0.5)
>>> m.insert_scan([0.2, 0.2, 0.2], [[0.2, 0.2, 3.2]])
>>> m.state([[0.2, 0.2, 1.2], [0.2, 0.2, 3.2], [0.2, 0.2, 5.2]]).tolist()
[0, 1, -1]
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from planners.occupancy.blocks import BlockStore
from planners.occupancy.logodds import UNKNOWN, Codec, LogOddsParams, probability
from planners.occupancy.projection import column_reduce
from planners.occupancy.raycast import traverse

Array = NDArray[np.float64]
DEFAULT_PARAMS = LogOddsParams()


class VoxelMap:
    """A sparse 3-D occupancy map in log-odds (OctoMap's sensor model, dense blocks instead of an octree)."""

    def __init__(self, resolution: float, params: LogOddsParams = DEFAULT_PARAMS, block: int = 16) -> None:
        if not resolution > 0:
            raise ValueError(f"resolution must be positive, got {resolution}")
        self.resolution = float(resolution)
        self.params = params
        self.codec = Codec(self.params)
        self.store = BlockStore(block)

    # --- updates -------------------------------------------------------------------------------------------

    def insert_scan(self, origin: ArrayLike, endpoints: ArrayLike, hit: ArrayLike | None = None,
                    max_range: float | None = None) -> None:
        """Fuse one ping: beams from `origin` (3,) to `endpoints` (N, 3), NED metres.

        `hit` (N,) is False for beams without a return (their endpoint is where they stop carving); beams longer
        than `max_range` are cut there and count as no-return. Non-finite endpoints are ignored.
        """
        o = np.asarray(origin, dtype=float).reshape(3)
        e = np.asarray(endpoints, dtype=float).reshape(-1, 3)
        returned = np.ones(len(e), dtype=bool) if hit is None else np.asarray(hit, dtype=bool).reshape(len(e))
        finite = np.isfinite(e).all(axis=1)
        if not finite.all():
            e, returned = e[finite], returned[finite]
        if max_range is not None:
            d = e - o
            length = np.linalg.norm(d, axis=1)
            far = length > max_range
            if far.any():
                e = e.copy()
                e[far] = o + d[far] * (max_range / length[far])[:, None]
                returned = returned & ~far
        if len(e) == 0 or not np.isfinite(o).all():
            return
        o_v, e_v = o / self.resolution, e / self.resolution
        store = self.store
        store.cover(np.floor(np.minimum(o_v, e_v.min(axis=0))), np.floor(np.maximum(o_v, e_v.max(axis=0))))
        offset = store.origin_key  # keys relative to it are non-negative inside the block index
        segments, moves = traverse(o_v, e_v, offset)
        total = sum(len(s.keys[0]) for s in segments)
        passed = np.empty(total + 1, dtype=np.int64)
        at = 0
        for s in segments:
            store.positions(s.keys, allocate=True, out=passed[at: at + len(s.keys[0])])
            at += len(s.keys[0])
        start = (np.floor(o_v).astype(np.int64) - offset).astype(np.int32)
        store.positions((start[:1], start[1:2], start[2:]), allocate=True, out=passed[total:])
        if not moves.any():
            passed = passed[:0]
        ends = (np.floor(e_v[returned]).astype(np.int64) - offset).astype(np.int32).T.copy()
        hits = store.positions((ends[0], ends[1], ends[2]), allocate=True)
        # Read the hit voxels before the free-space update: a voxel both passed and hit counts as hit only.
        pool, codec = store.pool, self.codec
        before_hit = pool.take(hits)
        pool[passed] = codec.after_miss.take(pool.take(passed))
        pool[hits] = codec.after_hit.take(before_hit)

    # --- queries -------------------------------------------------------------------------------------------

    def keys(self, points: ArrayLike) -> NDArray[np.int64]:
        """Voxel keys (N, 3) of points (N, 3) in metres."""
        return np.floor(np.asarray(points, dtype=float).reshape(-1, 3) / self.resolution).astype(np.int64)

    def centres(self, keys: ArrayLike) -> Array:
        """Centres (N, 3) in metres of voxels given by keys."""
        return (np.asarray(keys, dtype=float).reshape(-1, 3) + 0.5) * self.resolution

    def _codes(self, points: ArrayLike) -> NDArray[np.uint16]:
        positions = self.store.lookup(self.keys(points))
        codes = np.full(len(positions), UNKNOWN, dtype=np.uint16)
        stored = positions >= 0
        codes[stored] = self.store.pool[positions[stored]]
        return codes

    def log_odds(self, points: ArrayLike) -> Array:
        """(N,) log-odds of the voxels holding the points; 0 where unknown."""
        return self.codec.log_odds[self._codes(points)].astype(float)

    def probability(self, points: ArrayLike) -> Array:
        """(N,) occupancy probability of the voxels holding the points; 0.5 where unknown."""
        return probability(self.log_odds(points))

    def state(self, points: ArrayLike) -> NDArray[np.int8]:
        """(N,) 1 occupied, 0 free, −1 unknown."""
        codes = self._codes(points)
        result = np.where(codes >= self.codec.occupied_code, 1, 0).astype(np.int8)
        result[codes == UNKNOWN] = -1
        return result

    def occupied_keys(self) -> NDArray[np.int64]:
        """Keys (K, 3) of all occupied voxels."""
        codes = self.store.used()
        return self.store.keys_of(np.flatnonzero(codes >= self.codec.occupied_code))

    def free_keys(self) -> NDArray[np.int64]:
        """Keys (K, 3) of all known, not occupied voxels."""
        codes = self.store.used()
        return self.store.keys_of(np.flatnonzero((codes < self.codec.occupied_code) & (codes != UNKNOWN)))

    def occupied_centres(self) -> Array:
        """Centres (K, 3) in metres of all occupied voxels."""
        return self.centres(self.occupied_keys())

    def free_centres(self) -> Array:
        """Centres (K, 3) in metres of all free voxels."""
        return self.centres(self.free_keys())

    @property
    def known_voxels(self) -> int:
        """Number of voxels observed at least once."""
        return int(np.count_nonzero(self.store.used()))

    @property
    def memory_bytes(self) -> int:
        """Bytes held by the allocated blocks and the block index."""
        return self.store.memory_bytes

    # --- 2-D products --------------------------------------------------------------------------------------

    def height_map(self, north_range: tuple[float, float], east_range: tuple[float, float], cell: float) -> Array:
        """Shallowest occupied depth per column: the seabed or object top as sensed (NaN where none is known).

        Cell (i, j) is centred at (north_range[0] + i·cell, east_range[0] + j·cell) and spans ±cell/2; the depth
        is that of the occupied voxel centre, so a flat seabed comes back within half a voxel.
        """
        centres = self.occupied_centres()
        return column_reduce(centres[:, 0], centres[:, 1], centres[:, 2], north_range, east_range, cell, "min")

    def occupancy_projection(self, north_range: tuple[float, float], east_range: tuple[float, float], cell: float,
                             mode: str = "count") -> Array:
        """Occupied voxels per column: `count` of them, or their `max_probability` (0 where none is occupied).

        Cells as in `height_map`.
        """
        keys = self.occupied_keys()
        centres = self.centres(keys)
        if mode == "count":
            values = np.ones(len(keys))
            return column_reduce(centres[:, 0], centres[:, 1], values, north_range, east_range, cell, "sum")
        if mode == "max_probability":
            values = self.probability(centres)
            grid = column_reduce(centres[:, 0], centres[:, 1], values, north_range, east_range, cell, "max")
            return np.nan_to_num(grid, nan=0.0)
        raise ValueError(f"unknown projection mode '{mode}' (expected 'count' or 'max_probability')")
