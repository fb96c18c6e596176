"""Sparse storage of the voxel occupancy map of seed 002 §2.1: dense blocks allocated only where beams reach.

A survey-sized map (300 × 400 m at 0.25 m with a 20 m water column) has ~10⁸ voxels in its bounding box, and the
sonar sees most of the water column, so storage must be both cheap per voxel and sparse at the scale of blocks.
Voxels live in cubes of block³ 16-bit codes (see `logodds`), allocated on first touch in one growing pool; a
dense int32 index over block coordinates (a few MB for a survey field; it grows with the mapped region) gives
each block's slot. A voxel key (integer voxel coordinates) maps to a pool position with shifts, masks and one
gather, for a whole array of keys at once.

The pool is zero-filled (0 = unknown) through `np.zeros`, so capacity not yet used costs address space, not
memory; `memory_bytes` counts the blocks in use and the index.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

IntArray = NDArray[np.int64]


class BlockStore:
    """Voxel codes (uint16) in lazily allocated blocks of `block`³ voxels (block a power of two, 2–64)."""

    def __init__(self, block: int = 16) -> None:
        if block < 2 or block > 64 or block & (block - 1):
            raise ValueError(f"block must be a power of two between 2 and 64, got {block}")
        self.block = block
        self.shift = block.bit_length() - 1
        self.mask = block - 1
        self.cells = block**3
        self.pool: NDArray[np.uint16] = np.zeros(0, dtype=np.uint16)
        self.block_keys: IntArray = np.zeros((0, 3), dtype=np.int64)
        """Block coordinates (voxel key // block) of each slot."""
        self.count = 0
        self.index: NDArray[np.int32] = np.full((0, 0, 0), -1, dtype=np.int32)
        self.lo: IntArray = np.zeros(3, dtype=np.int64)
        """Block coordinates of index[0, 0, 0]."""
        self.data_lo: IntArray = np.zeros(3, dtype=np.int64)
        self.data_hi: IntArray = np.zeros(3, dtype=np.int64)
        """Bounds (inclusive, block coordinates) of everything asked to be covered so far; the index adds slack."""

    @property
    def origin_key(self) -> IntArray:
        """Voxel key of the index's first voxel: keys relative to it are the non-negative `rel` keys below."""
        return self.lo * self.block

    @property
    def extent(self) -> IntArray:
        """Index size in voxels along each axis (relative keys lie in [0, extent))."""
        return np.asarray(self.index.shape, dtype=np.int64) * self.block

    @property
    def memory_bytes(self) -> int:
        return int(self.count * self.cells * self.pool.itemsize + self.index.nbytes + self.count * 3 * 8)

    def cover(self, key_min: ArrayLike, key_max: ArrayLike) -> None:
        """Grow the index to hold voxel keys in [key_min, key_max] (inclusive), with slack for what comes next."""
        b_min = np.asarray(key_min, dtype=np.int64) >> self.shift
        b_max = np.asarray(key_max, dtype=np.int64) >> self.shift
        if self.index.size:
            b_min, b_max = np.minimum(self.data_lo, b_min), np.maximum(self.data_hi, b_max)
        self.data_lo, self.data_hi = b_min, b_max
        shape = np.asarray(self.index.shape, dtype=np.int64)
        if self.index.size and (b_min >= self.lo).all() and (b_max < self.lo + shape).all():
            return
        # One block of margin at least (relative coordinates stay positive), and an eighth of the extent more
        # so that a map that keeps growing is re-indexed only a logarithmic number of times.
        slack = 1 + (b_max - b_min + 1) // 8
        lo, hi = b_min - slack, b_max + slack
        index = np.full(tuple(int(v) for v in hi - lo + 1), -1, dtype=np.int32)
        if self.count:
            b = self.block_keys[: self.count] - lo
            index[b[:, 0], b[:, 1], b[:, 2]] = np.arange(self.count, dtype=np.int32)
        self.index, self.lo = index, lo

    def positions(self, rel: tuple[NDArray[np.int32], NDArray[np.int32], NDArray[np.int32]], allocate: bool,
                  out: IntArray | None = None) -> IntArray:
        """Pool positions of voxels given by int32 keys relative to `origin_key` (inside the index).

        Voxels in blocks not yet allocated get a new block (`allocate`) or position −1.
        """
        s, m = self.shift, self.mask
        _, ny, nz = self.index.shape
        flat_block = rel[0] >> s
        flat_block *= ny
        flat_block += rel[1] >> s
        flat_block *= nz
        flat_block += rel[2] >> s
        index = self.index.reshape(-1)
        slot = index.take(flat_block)
        missing = slot < 0 if len(slot) and slot.min() < 0 else None
        if missing is not None and allocate:
            self._allocate(np.unique(flat_block[missing]))
            slot[missing] = index.take(flat_block[missing])
        local = (rel[0] & m) << (2 * s)
        local |= (rel[1] & m) << s
        local |= rel[2] & m
        result = np.multiply(slot, self.cells, out=out, dtype=np.int64)
        result += local
        if missing is not None and not allocate:
            result[missing] = -1
        return result

    def lookup(self, keys: ArrayLike) -> IntArray:
        """Pool positions of voxels by absolute keys (N, 3); −1 where not stored."""
        k = np.asarray(keys, dtype=np.int64).reshape(-1, 3)
        rel = k - self.origin_key
        inside = ((rel >= 0) & (rel < self.extent)).all(axis=1)
        result = np.full(len(k), -1, dtype=np.int64)
        if self.count and inside.any():
            r = rel[inside]
            r32 = r.astype(np.int32)
            result[inside] = self.positions((r32[:, 0], r32[:, 1], r32[:, 2]), allocate=False)
        return result

    def keys_of(self, positions: ArrayLike) -> IntArray:
        """Absolute voxel keys (N, 3) of pool positions."""
        p = np.asarray(positions, dtype=np.int64)
        slot, local = p // self.cells, p % self.cells
        s, m = self.shift, self.mask
        offsets = np.stack([(local >> (2 * s)) & m, (local >> s) & m, local & m], axis=1)
        return self.block_keys[slot] * self.block + offsets

    def used(self) -> NDArray[np.uint16]:
        """The codes of all allocated blocks (a view; position i is pool position i)."""
        return self.pool[: self.count * self.cells]

    def _allocate(self, flat_blocks: IntArray) -> None:
        n = len(flat_blocks)
        need = self.count + n
        capacity = len(self.block_keys)
        if need > capacity:
            capacity = max(need, 2 * capacity, 64)  # zero pages past `count` cost no memory until used
            pool = np.zeros(capacity * self.cells, dtype=np.uint16)
            pool[: self.count * self.cells] = self.pool[: self.count * self.cells]
            keys = np.zeros((capacity, 3), dtype=np.int64)
            keys[: self.count] = self.block_keys[: self.count]
            self.pool, self.block_keys = pool, keys
        _, ny, nz = self.index.shape
        bx, rest = np.divmod(flat_blocks, ny * nz)
        by, bz = np.divmod(rest, nz)
        self.block_keys[self.count: need] = np.stack([bx, by, bz], axis=1) + self.lo
        self.index.reshape(-1)[flat_blocks] = np.arange(self.count, need, dtype=np.int32)
        self.count = need
