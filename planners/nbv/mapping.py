"""The map upkeep both NBV planners share (ours and the receding-horizon baseline): a dense state window over
the exploration box, the derived safety maps, and fusing scans into them (seed 002 §2.2.2)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from planners.nbv.derived import DerivedMaps
from planners.nbv.grid import StateGrid
from planners.nbv.views import Scanner
from planners.occupancy import VoxelMap
from planners.rrt import ClearanceGrid

if TYPE_CHECKING:
    from planners.nbv.planner import Scan


class MapKeeping:
    """Mixin for planner dataclasses with `voxel_map`, `lo`, `hi`, `scanner`, `safety_cell` and `seed` fields;
    call `_init_maps()` from `__post_init__`."""

    voxel_map: VoxelMap
    lo: ArrayLike
    hi: ArrayLike
    scanner: Scanner
    safety_cell: float | None
    seed: int | None
    grid: StateGrid
    derived: DerivedMaps
    returns: NDArray[np.bool_]

    def _init_maps(self) -> None:
        self.grid = StateGrid.over(self.voxel_map, self.lo, self.hi)
        self.derived = DerivedMaps(self.grid, self.safety_cell or max(0.5, 2.0 * self.grid.resolution))
        self.rng = np.random.default_rng(self.seed)
        self.returns = np.zeros(self.grid.shape, dtype=bool)
        """Voxels of the state window in which a beam has ended (a return), whatever their state now."""

    @property
    def safety(self) -> ClearanceGrid:
        """Clearance from occupied and (mostly) unknown space, for candidates and the paths between views."""
        return self.derived.safety

    def integrate(self, scan: Scan) -> None:
        """Fuse one scan into the map (free along beams, occupied at returns), the dense window and the safety
        grid (clearance from occupied and unknown voxels)."""
        self.voxel_map.insert_scan(scan.origin, scan.endpoints, scan.hit, max_range=self.scanner.max_range)
        ijk, inside = self.grid.index(scan.endpoints[scan.hit])
        self.returns[tuple(ijk[inside].T)] = True
        box = self.grid.refresh(self.voxel_map, scan.origin, scan.endpoints)
        if box is not None:
            self.derived.update(*box)
