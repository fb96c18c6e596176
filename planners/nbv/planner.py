"""The next-best-view planner an explore agent drives step by step (seed 002 §2.2.2, Fig. 6).

The seed's cycle: put the vehicle at a safe starting pose; at each view the scan goes into the voxel model;
candidates are generated near the safe trajectory, in safe free space; their visibility and utility are
computed; the vehicle moves to the best along a safe route (RRT) and scans again. `NbvPlanner` holds the map and
does the middle of that cycle:

* `integrate(scan)`: Bayes (log-odds) update of the `VoxelMap`, refresh of the dense state window and of the
  safety grid (clearance from occupied and unknown voxels, for candidates and the RRT between views);
* `propose(pose)`: candidates → visibility → utility → the best view, or None when no candidate would reveal at
  least `min_unknown` unknown voxels (nothing left worth a move). With `shortlist` set, every candidate is first
  cast with a sparse ray grid (`prescreen_rays`, a sixth of the rays or so) and only the `shortlist` with the
  most unknown and contour voxels in it are cast in full: the utility ranks the informative candidates, and an
  iteration's ray casting shrinks about threefold;
* `extra_candidates()`, `extra_gain(views)`, `with_extra(u, extra)`: hooks for a goal besides mapping (the
  `reconstruct` goal's stereo coverage): more candidates, and a count per candidate that joins the pre-screen's
  ranking and the utility; by default none;
* `reject(view)`: the agent could not reach a proposed view; candidates near it are skipped from then on.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from planners.nbv.candidates import candidate_views
from planners.nbv.derived import DerivedMaps
from planners.nbv.grid import StateGrid
from planners.nbv.mapping import MapKeeping
from planners.nbv.utility import ViewTerms, Weights, view_utility
from planners.nbv.views import Scanner, View, Views
from planners.nbv.visibility import visibility
from planners.occupancy import VoxelMap

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Scan:
    """One scanner frame: beams from `origin` to `endpoints` (N, 3); `hit` False where a beam returned nothing
    (its endpoint is then at the maximum range)."""

    origin: Array
    endpoints: Array
    hit: NDArray[np.bool_]


@dataclass
class Proposal:
    """What the last `propose` looked at (for plots and logs)."""

    candidates: Views
    terms: ViewTerms | None
    chosen: int
    seconds: float


@dataclass
class NbvPlanner(MapKeeping):
    """Next-best-view scanning with the seed's utility over a voxel map, inside the box [lo, hi]."""

    voxel_map: VoxelMap
    lo: ArrayLike
    hi: ArrayLike
    scanner: Scanner
    weights: Weights = field(default_factory=Weights)
    safe_distance: float = 5.0
    candidates: int = 200
    band: float | None = None
    min_overlap: float = 0.1
    min_unknown: int = 20
    min_extra: int = 1
    """With an `extra_gain`, a view that adds at least this much is still worth the move."""
    candidate_rounds: int = 40
    shortlist: int | None = None
    """Candidates cast with every ray after the sparse pre-screen (None: all of them, no pre-screen)."""
    prescreen_rays: tuple[int, int] = (10, 8)
    """Sampling rounds (8 × `candidates` draws each) before settling for fewer candidates."""
    safety_cell: float | None = None
    """Safety-grid block size (m); default max(0.5, 2 voxels)."""
    seed: int | None = None
    last: Proposal | None = None
    grid: StateGrid = field(init=False)
    derived: DerivedMaps = field(init=False)
    rejected: list[Array] = field(default_factory=list)

    def __post_init__(self) -> None:
        self._init_maps()

    def propose(self, pose: View) -> View | None:
        """The next best view from `pose`, or None when no candidate would reveal `min_unknown` voxels."""
        t0 = time.perf_counter()
        grid, contour = self.utility_grid()
        views = self.mounted(candidate_views(grid, self.safety, pose.point, self.scanner, count=self.candidates,
                                             safe_distance=self.safe_distance, band=self.band, rng=self.rng,
                                             contour=contour, max_rounds=self.candidate_rounds))
        more = self.extra_candidates()
        if more is not None and len(more):
            views = Views(np.concatenate([views.positions, more.positions]),
                          np.concatenate([views.heading_deg, more.heading_deg]),
                          np.concatenate([views.pitch_deg, more.pitch_deg]))
        if self.rejected and len(views):
            near = np.min(np.linalg.norm(views.positions[:, None, :] - np.asarray(self.rejected)[None], axis=2),
                          axis=1)
            views = views.select(near > self.grid.resolution * 2.0)
        if not len(views):
            self.last = Proposal(views, None, -1, time.perf_counter() - t0)
            return None
        extra = self.extra_gain(views)
        if self.shortlist is not None and len(views) > self.shortlist:
            sparse = visibility(grid, views, self.scanner.with_rays(self.prescreen_rays), contour=contour)
            gain = sparse.unknown / max(int(sparse.unknown.max()), 1) + sparse.contour / max(int(sparse.contour.max()),
                                                                                             1)
            if extra is not None:
                gain = gain + extra / max(int(extra.max()), 1)
            keep = np.sort(np.argsort(-gain, kind="stable")[: self.shortlist])
            views = views.select(keep)
            extra = None if extra is None else extra[keep]
        terms = view_utility(grid, views, pose.point, self.scanner, self.weights, min_overlap=self.min_overlap,
                             contour=contour)
        # A view that would reveal nothing and follow no contour is not worth the move, however near it is.
        if extra is None:
            best = int(np.argmax(np.where((terms.f > 0) | (terms.ct > 0), terms.u, -1.0)))
        else:
            u = self.with_extra(terms.u, extra)
            best = int(np.argmax(np.where((terms.f > 0) | (terms.ct > 0) | (extra > 0), u, -1.0)))
        self.last = Proposal(views, terms, best, time.perf_counter() - t0)
        if terms.f.max() < self.min_unknown and (extra is None or int(extra.max()) < self.min_extra):
            return None
        return views[best]

    def extra_candidates(self) -> Views | None:
        """Candidates a goal besides mapping adds to the shell's (mounted as the sensor allows); None: none."""
        return None

    def extra_gain(self, views: Views) -> NDArray[np.int64] | None:
        """A count per candidate that a goal besides mapping adds to the utility (`with_extra`); None: none."""
        return None

    def with_extra(self, u: NDArray[np.float64], extra: NDArray[np.int64]) -> NDArray[np.float64]:
        """The utility with the `extra_gain` counts in it (a subclass that has them says how)."""
        return u

    def utility_grid(self) -> tuple[StateGrid, NDArray[np.int64]]:
        """The state grid candidates and the utility see, and the contour voxel ids that count (a subclass may
        narrow them to a region of interest)."""
        return self.grid, self.derived.contour_ids()

    def mounted(self, views: Views) -> Views:
        """Candidates as the sensor's mount allows them (here: as generated)."""
        return views

    def reject(self, view: View) -> None:
        """Mark a proposed view as unreachable."""
        self.rejected.append(view.point)
