"""Maps derived from the voxel states for next-best-view scanning, kept up to date region by region
(seed 002 §2.2.2): the open contour of the known structure (the ct term) and the safety grid (safe limits near
occupied voxels, for candidates and the RRT between views).

A scan changes voxels only inside its own bounding box, and both products are local (a voxel's contour status
depends on its 2-neighbourhood; a block's safety state on its own voxels), so after each scan only that box is
recomputed; the safety grid's distance transform then runs on the blocks (0.5 m by default), which are few.
That keeps an iteration well under a second at 0.1 m voxels, where a full recomputation would not be.

>>> import numpy as np
>>> states = np.zeros((5, 5, 5), dtype=np.int8); states[2, 2, 2] = 1; states[2, 2, 3] = -1; states[2, 2, 4] = 1
>>> contour_mask(states)[2, 2].tolist()           # the unknown voxel touches free space: both neighbours count
[False, False, True, False, True]
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from planners.nbv.grid import FREE, OCCUPIED, UNKNOWN, StateGrid
from planners.rrt import ClearanceGrid

BoolArray = NDArray[np.bool_]


def _dilate(mask: BoolArray, faces_only: bool) -> BoolArray:
    """OR of each voxel's neighbours (6 face neighbours, or the full 3×3×3 cube), the voxel itself excluded for
    faces and included for the cube."""
    out = np.zeros_like(mask) if faces_only else mask.copy()
    for axis in range(3):
        lo = [slice(None)] * 3
        hi = [slice(None)] * 3
        lo[axis], hi[axis] = slice(None, -1), slice(1, None)
        src = mask if faces_only else out.copy()
        out[tuple(lo)] |= src[tuple(hi)]
        out[tuple(hi)] |= src[tuple(lo)]
    return out


def contour_mask(states: NDArray[np.int8]) -> BoolArray:
    """Occupied voxels with a frontier voxel (unknown, with a free face neighbour) among their 26 neighbours.

    The unknown inside a scanned object touches no free voxel, so a fully scanned surface has no contour left.
    """
    frontier = (states == UNKNOWN) & _dilate(states == FREE, faces_only=True)
    return np.asarray((states == OCCUPIED) & _dilate(frontier, faces_only=False), dtype=bool)


class DerivedMaps:
    """The contour mask and the safety blocks of a `StateGrid`, updated after each refresh."""

    def __init__(self, grid: StateGrid, safety_cell: float = 0.5, unknown_share: float = 0.75) -> None:
        self.grid = grid
        self.k = max(1, int(round(safety_cell / grid.resolution)))
        self.unknown_share = unknown_share
        self.contour = contour_mask(grid.states)
        self.blocks = tuple(-(-n // self.k) for n in grid.shape)
        self.obstacle = np.zeros(self.blocks, dtype=bool)
        self._blocks(np.zeros(3, dtype=np.int64), np.asarray(self.blocks))
        self._safety: ClearanceGrid | None = None

    def update(self, lo: NDArray[np.int64], hi: NDArray[np.int64]) -> None:
        """Recompute what voxels in the index box [lo, hi) can have changed."""
        shape = np.asarray(self.grid.shape)
        inner_lo, inner_hi = np.maximum(lo - 2, 0), np.minimum(hi + 2, shape)
        read_lo, read_hi = np.maximum(inner_lo - 2, 0), np.minimum(inner_hi + 2, shape)
        sub = self.grid.states[read_lo[0]:read_hi[0], read_lo[1]:read_hi[1], read_lo[2]:read_hi[2]]
        mask = contour_mask(sub)
        a, b = inner_lo - read_lo, inner_hi - read_lo
        self.contour[inner_lo[0]:inner_hi[0], inner_lo[1]:inner_hi[1], inner_lo[2]:inner_hi[2]] = \
            mask[a[0]:b[0], a[1]:b[1], a[2]:b[2]]
        self._blocks(lo // self.k, -(-hi // self.k))
        self._safety = None

    def contour_ids(self) -> NDArray[np.int64]:
        """Flat ids of the contour voxels."""
        return np.flatnonzero(self.contour).astype(np.int64)

    @property
    def safety(self) -> ClearanceGrid:
        """Clearance from blocks (about `safety_cell` wide) that hold an occupied voxel or are mostly unknown.

        Beams fan out, so space they crossed is speckled with unknown voxels between them, and a hidden object big
        enough to matter would have stopped some beams: a block counts as unknown only when more than
        `unknown_share` of it is. Conservative for occupied voxels by construction.
        """
        if self._safety is None:
            self._safety = ClearanceGrid.from_occupancy(self.obstacle, self.grid.origin,
                                                        self.grid.resolution * self.k)
        return self._safety

    def _blocks(self, b_lo: NDArray[np.int64], b_hi: NDArray[np.int64]) -> None:
        k = self.k
        v_lo, v_hi = b_lo * k, b_hi * k
        sub = np.full(tuple(int(v) for v in v_hi - v_lo), UNKNOWN, dtype=np.int8)  # past the grid is unknown
        src_hi = np.minimum(v_hi, np.asarray(self.grid.shape))
        ext = src_hi - v_lo
        sub[:ext[0], :ext[1], :ext[2]] = self.grid.states[v_lo[0]:src_hi[0], v_lo[1]:src_hi[1], v_lo[2]:src_hi[2]]
        a, b, c = (int(v) for v in b_hi - b_lo)
        blocks = sub.reshape(a, k, b, k, c, k)
        occupied = (blocks == OCCUPIED).any(axis=(1, 3, 5))
        unknown = (blocks == UNKNOWN).sum(axis=(1, 3, 5), dtype=np.int32) > self.unknown_share * k**3
        self.obstacle[b_lo[0]:b_hi[0], b_lo[1]:b_hi[1], b_lo[2]:b_hi[2]] = occupied | unknown
