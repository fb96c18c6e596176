"""A receding-horizon next-best-view baseline in the style of Bircher et al. 2016 ("Receding Horizon
'Next-Best-View' Planner for 3D Exploration", ICRA), for the seed 002 §2.2.2 benchmark.

Each iteration grows an RRT of viewpoints from the current pose in known-free space: edges straight and safe as
in `explore.segment_safe` (the same safety grid and criterion as our planner), at most `extension` metres; a
node's yaw uniform, its pitch uniform within the same limit our candidates use. A node's gain is

    gain(n) = gain(parent) + unmapped(n) · exp(−λ · cost(n)),   λ = 0.5,

with unmapped(n) the unknown volume (m³) its scanner frustum would see (the same `visibility` ray casting our
planner uses) and cost(n) the path length from the root. The tree grows until it has `min_nodes` nodes and a
gain above `g_zero` (0 by default, as NBVP's `zero_gain`), or `max_nodes`. Only the first edge of the best branch
is executed; the rest of that branch seeds the next iteration's tree. Exploration ends when the best gain stays
at or below `g_zero`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from planners.nbv.candidates import is_safe_view
from planners.nbv.derived import DerivedMaps
from planners.nbv.explore import segment_safe
from planners.nbv.grid import FREE, StateGrid
from planners.nbv.mapping import MapKeeping
from planners.nbv.views import Scanner, View, Views
from planners.nbv.visibility import visibility
from planners.occupancy import VoxelMap

Array = NDArray[np.float64]


@dataclass
class RecedingHorizonNbv(MapKeeping):
    """Bircher-style receding-horizon NBV over a voxel map inside the box [lo, hi]."""

    voxel_map: VoxelMap
    lo: ArrayLike
    hi: ArrayLike
    scanner: Scanner
    safe_distance: float = 5.0
    lam: float = 0.5
    extension: float = 3.0
    min_nodes: int = 15
    max_nodes: int = 80
    g_zero_voxels: float = 0.0
    max_pitch_deg: float = 30.0
    batch: int = 8
    safety_cell: float | None = None
    """Safety-grid block size (m); default max(0.5, 2 voxels)."""
    seed: int | None = None
    grid: StateGrid = field(init=False)
    derived: DerivedMaps = field(init=False)
    branch: list[View] = field(default_factory=list)
    rejected: list[Array] = field(default_factory=list)
    last_nodes: int = 0

    def __post_init__(self) -> None:
        self._init_maps()

    def reject(self, view: View) -> None:
        self.rejected.append(view.point)
        self.branch = []

    def propose(self, pose: View) -> View | None:
        """The end of the first edge of the best branch, or None when no branch gains `g_zero`."""
        voxel = self.grid.resolution**3
        g_zero = self.g_zero_voxels * voxel
        nodes: list[View] = [pose]
        parent, cost, gain = [-1], [0.0], [0.0]
        for view in self.branch:  # the rest of the last best branch, as far as it is still safe
            if not self._edge_ok(nodes[-1].point, view.point):
                break
            nodes.append(view)
            parent.append(len(nodes) - 2)
            cost.append(cost[-1] + float(np.linalg.norm(view.point - nodes[-2].point)))
            gain.append(0.0)
        self._score(nodes, parent, cost, gain, range(1, len(nodes)), voxel)
        lo, hi = self.grid.origin + self.grid.resolution, self.grid.upper - self.grid.resolution
        tries = 0
        while len(nodes) < self.max_nodes and tries < 50 * self.max_nodes:
            if len(nodes) >= self.min_nodes and max(gain) > g_zero:
                break
            added = []
            for _ in range(self.batch):
                tries += 1
                target = self.rng.uniform(lo, hi)
                points = np.array([n.position for n in nodes])
                near = int(np.argmin(np.linalg.norm(points - target, axis=1)))
                d = target - points[near]
                dist = float(np.linalg.norm(d))
                if dist < 1e-9:
                    continue
                p = points[near] + d * min(1.0, self.extension / dist)
                if self.rejected and np.min(np.linalg.norm(np.asarray(self.rejected) - p, axis=1)) < 1.0:
                    continue
                if not self._edge_ok(points[near], p):
                    continue
                nodes.append(View.at(p, float(self.rng.uniform(0.0, 360.0)),
                                     float(self.rng.uniform(-self.max_pitch_deg, self.max_pitch_deg))))
                parent.append(near)
                cost.append(cost[near] + float(np.linalg.norm(p - points[near])))
                gain.append(0.0)
                added.append(len(nodes) - 1)
            self._score(nodes, parent, cost, gain, added, voxel)
        self.last_nodes = len(nodes)
        best = int(np.argmax(gain))
        if best == 0 or gain[best] <= g_zero:
            self.branch = []
            return None
        chain = [best]
        while parent[chain[-1]] != 0:
            chain.append(parent[chain[-1]])
        chain.reverse()
        self.branch = [nodes[i] for i in chain[1:]]
        return nodes[chain[0]]

    def _edge_ok(self, a: Array, b: Array) -> bool:
        """The node is in known-free space and as safe as our candidates (`is_safe_view`); the edge keeps the
        distance."""
        free = bool(self.grid.state(b[None])[0] == FREE)
        return (free and bool(is_safe_view(self.safety, b[None], self.safe_distance)[0])
                and segment_safe(self.safety, a, b, self.safe_distance))

    def _score(self, nodes: list[View], parent: list[int], cost: list[float], gain: list[float],
               new: range | list[int], voxel: float) -> None:
        """Gains of new nodes (parents always precede their children)."""
        idx = list(new)
        if not idx:
            return
        vis = visibility(self.grid, Views.of([nodes[i] for i in idx]), self.scanner,
                         contour=self.derived.contour_ids())
        for i, unknown in zip(idx, vis.unknown, strict=True):
            gain[i] = gain[parent[i]] + float(unknown) * voxel * math.exp(-self.lam * cost[i])
