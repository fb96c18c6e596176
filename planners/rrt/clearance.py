"""The clearance grid RRT planning runs in (seed 002 §2.2.1–2.2.2: safe routes in the occupancy map).

Each voxel of a dense grid holds a lower bound on the distance from *any point inside it* to *any point of any
obstacle voxel* (occupied, and unknown when unknown space is treated as unsafe). Two axis-aligned voxels of side
c whose integer offsets are (Δi, Δj, Δk) are at least c·sqrt(Σ max(0, |Δ| − 1)²) apart, which is exactly the
centre-to-centre distance from the first voxel to the obstacle grown by one voxel in every direction (a 3×3×3
dilation). So one binary dilation and one Euclidean distance transform (scipy, no loop over obstacles) give the
bound for every voxel, and the validity test of a state is a single lookup.

>>> import numpy as np
>>> occ = np.zeros((9, 3, 3), dtype=bool); occ[0] = True
>>> g = ClearanceGrid.from_occupancy(occ, origin=(0, 0, 0), cell=1.0)
>>> g.distance[:4, 1, 1].tolist()   # voxel 1 touches the obstacle; voxel 3 is ≥ 2 m from any point of it
[0.0, 0.0, 1.0, 2.0]
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage

Array = NDArray[np.float64]
Unknown = Literal["obstacle", "free", "forbid"]
"""How unknown voxels count: as obstacles (kept clear of by the safety distance), as free space, or forbidden
themselves but not kept clear of (the vehicle stays in known space; only occupied voxels need the distance)."""


@dataclass(frozen=True)
class ClearanceGrid:
    """Distances (m, float32, +inf with no obstacle) on a dense grid; voxel (i, j, k) spans origin + [i, i+1)·cell.

    Axes are north, east, down (local NED); `origin` is the corner of voxel (0, 0, 0).
    """

    distance: NDArray[np.float32]
    origin: Array
    cell: float

    @classmethod
    def from_occupancy(cls, obstacle: ArrayLike, origin: ArrayLike, cell: float) -> ClearanceGrid:
        """From a boolean obstacle grid (True = the vehicle may not be there)."""
        occ = np.asarray(obstacle, dtype=bool)
        if occ.ndim != 3:
            raise ValueError(f"obstacle grid must be 3-D, got shape {occ.shape}")
        if not cell > 0:
            raise ValueError(f"cell must be positive, got {cell}")
        if not occ.any():
            dist = np.full(occ.shape, np.inf, dtype=np.float32)
        else:
            grown = ndimage.binary_dilation(occ, structure=np.ones((3, 3, 3), dtype=bool))
            dist = (ndimage.distance_transform_edt(~grown) * cell).astype(np.float32)
        return cls(dist, np.asarray(origin, dtype=float).reshape(3), float(cell))

    @classmethod
    def from_states(cls, states: ArrayLike, origin: ArrayLike, cell: float, unknown: Unknown = "obstacle",
                    coarsen: int = 1) -> ClearanceGrid:
        """From a voxel state grid (1 occupied, 0 free, −1 unknown; `VoxelMap.state`'s convention).

        `coarsen` > 1 merges blocks of coarsen³ voxels, a block being an obstacle if any of its voxels is: the
        bound stays conservative and planning at 0.1 m maps gets a grid 1/coarsen³ the size.
        """
        s = np.asarray(states)
        obstacle = (s == 1) | (s == -1) if unknown == "obstacle" else s == 1
        if coarsen > 1:  # the part of the last blocks past the grid is unknown: an obstacle if unknown is one
            obstacle = _any_pool(obstacle, coarsen, pad=unknown == "obstacle")
        grid = cls.from_occupancy(obstacle, origin, cell * coarsen)
        if unknown == "forbid":
            forbidden = s == -1
            grid.distance[_any_pool(forbidden, coarsen, pad=True) if coarsen > 1 else forbidden] = 0.0
        return grid

    @classmethod
    def from_voxel_map(cls, voxel_map: VoxelStates, lo: ArrayLike, hi: ArrayLike, unknown: Unknown = "obstacle",
                       coarsen: int = 1) -> ClearanceGrid:
        """From a `planners.occupancy.VoxelMap` over the box [lo, hi] (metres), snapped outwards to its voxels."""
        res = float(voxel_map.resolution)
        k_lo = np.floor(np.asarray(lo, dtype=float) / res).astype(np.int64)
        k_hi = np.ceil(np.asarray(hi, dtype=float) / res).astype(np.int64)
        shape = tuple(int(v) for v in np.maximum(k_hi - k_lo, 1))
        idx = np.indices(shape).reshape(3, -1).T
        states = voxel_map.state((idx + k_lo + 0.5) * res).reshape(shape)
        return cls.from_states(states, k_lo * res, res, unknown=unknown, coarsen=coarsen)

    @property
    def shape(self) -> tuple[int, int, int]:
        s = self.distance.shape
        return int(s[0]), int(s[1]), int(s[2])

    @property
    def upper(self) -> Array:
        """The far corner of the grid (metres)."""
        return self.origin + np.asarray(self.shape, dtype=float) * self.cell

    def indices(self, points: ArrayLike) -> tuple[NDArray[np.int64], NDArray[np.bool_]]:
        """Voxel indices (N, 3) of points (N, 3) and whether each lies inside the grid."""
        p = np.asarray(points, dtype=float).reshape(-1, 3)
        ijk = np.floor((p - self.origin) / self.cell).astype(np.int64)
        inside: NDArray[np.bool_] = np.asarray(((ijk >= 0) & (ijk < np.asarray(self.shape))).all(axis=1))
        return ijk, inside

    def at(self, points: ArrayLike) -> Array:
        """(N,) clearance bound at points; 0 outside the grid."""
        ijk, inside = self.indices(points)
        out = np.zeros(len(ijk))
        i = ijk[inside]
        out[inside] = self.distance[i[:, 0], i[:, 1], i[:, 2]]
        return out

    def safe(self, points: ArrayLike, safety_distance: float) -> NDArray[np.bool_]:
        """(N,) True where every point of the voxel holding the point is ≥ `safety_distance` from obstacles."""
        return self.at(points) >= safety_distance

    def free_mask(self, safety_distance: float) -> NDArray[np.bool_]:
        """The grid of safe voxels."""
        return np.asarray(self.distance >= safety_distance)


class VoxelStates(Protocol):
    """What `from_voxel_map` needs of a voxel map (`planners.occupancy.VoxelMap` provides it)."""

    @property
    def resolution(self) -> float: ...

    def state(self, points: ArrayLike) -> NDArray[np.int8]: ...


def _any_pool(mask: NDArray[np.bool_], k: int, pad: bool = False) -> NDArray[np.bool_]:
    """Block-wise OR over k×k×k blocks (the grid padded with `pad` to a multiple of k)."""
    shape = [math.ceil(n / k) * k for n in mask.shape]
    padded = np.full(shape, pad, dtype=bool)
    padded[: mask.shape[0], : mask.shape[1], : mask.shape[2]] = mask
    a, b, c = (n // k for n in shape)
    return np.asarray(padded.reshape(a, k, b, k, c, k).any(axis=(1, 3, 5)))
