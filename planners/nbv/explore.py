"""The exploration loop of seed 002 §2.2.2 (Fig. 6), for any view planner: scan, propose, move safely, repeat.

`run_exploration` is the harness both our planner and the receding-horizon baseline run in: the same sensor
callback, the same safe connection between views (`connect`: the straight segment when every point of it keeps
`safe_distance` from occupied and (mostly) unknown space, otherwise an RRT* path from `planners.rrt` on the same
safety grid), and the same stopping rules (the planner has nothing left, the path budget, a coverage target when
a coverage callback is given, a number of views). The vehicle scans once at each view it reaches. `explore`
builds an `NbvPlanner` and runs it.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from planners.nbv.candidates import is_safe
from planners.nbv.grid import StateGrid
from planners.nbv.planner import NbvPlanner, Scan
from planners.nbv.utility import Weights
from planners.nbv.views import Scanner, View
from planners.occupancy import VoxelMap, ray_voxels
from planners.rrt import ClearanceGrid, plan_path

Array = NDArray[np.float64]
CONNECT_ITERATIONS = 4000  # RRT* iterations per connection: about 0.3 s here


class ViewPlanner(Protocol):
    """What the harness drives: `NbvPlanner` and `baseline.RecedingHorizonNbv`."""

    @property
    def grid(self) -> StateGrid: ...

    @property
    def safety(self) -> ClearanceGrid: ...

    def integrate(self, scan: Scan) -> None: ...

    def propose(self, pose: View) -> View | None: ...

    def reject(self, view: View) -> None: ...


@dataclass
class Step:
    """One view reached: the path flown to it, the totals after its scan, and the time spent."""

    view: View
    path: Array
    path_length: float
    """Cumulative path length (m) after reaching this view."""
    coverage: float | None
    plan_s: float
    """Seconds the planner spent on this iteration (integrate + propose)."""
    connect_s: float


@dataclass
class ExplorationLog:
    steps: list[Step] = field(default_factory=list)
    stop_reason: str = ""
    rejected: int = 0

    @property
    def path_length(self) -> float:
        return self.steps[-1].path_length if self.steps else 0.0

    @property
    def path(self) -> Array:
        parts = [s.path for s in self.steps if len(s.path)]
        return np.concatenate(parts) if parts else np.zeros((0, 3))

    def coverage_curve(self) -> tuple[Array, Array]:
        """(path length, coverage) after each view."""
        return (np.array([s.path_length for s in self.steps]),
                np.array([np.nan if s.coverage is None else s.coverage for s in self.steps]))

    def length_at(self, coverage: float) -> float | None:
        """Path length at which the coverage first reached `coverage` (None if it never did)."""
        for s in self.steps:
            if s.coverage is not None and s.coverage >= coverage:
                return s.path_length
        return None

    def iteration_seconds(self) -> Array:
        return np.array([s.plan_s for s in self.steps[1:]])


def segment_safe(safety: ClearanceGrid, a: ArrayLike, b: ArrayLike, safe_distance: float) -> bool:
    """Every point of the straight segment a→b keeps `safe_distance`: every cell of the safety grid it passes
    through (exact traversal, `planners.occupancy.ray_voxels`) has a clearance bound of at least that."""
    o = safety.origin
    pa, pb = np.asarray(a, dtype=float) - o, np.asarray(b, dtype=float) - o
    _, keys = ray_voxels(pa, pb[None], safety.cell)
    keys = np.concatenate([keys, np.floor(np.stack([pa, pb]) / safety.cell).astype(np.int64)])
    inside = ((keys >= 0) & (keys < np.asarray(safety.shape))).all(axis=1)
    if not inside.all():
        return False
    return bool((safety.distance[keys[:, 0], keys[:, 1], keys[:, 2]] >= safe_distance).all())


def connect(safety: ClearanceGrid, a: ArrayLike, b: ArrayLike, safe_distance: float, *,
            iterations: int = CONNECT_ITERATIONS, time_limit_s: float = 3.0, seed: int | None = None) -> Array | None:
    """A safe path (K, 3) from a to b: the straight segment when it is safe, else RRT* (`planners.rrt`); or None.

    RRT* runs a fixed number of `iterations` (about 0.3 s here) so that, with a `seed`, the same map gives the
    same path whatever the machine's load; `time_limit_s` only caps a pathological run.

    A scan can reveal structure that lowers the grid's (conservative, block-wise) clearance bound at the vehicle
    below the RRT's validity threshold although it still keeps the safety distance; the path then starts with a
    short escape segment to a valid point (`escape`).
    """
    pa, pb = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    head: list[Array] = []
    if not is_safe(safety, pa[None], safe_distance)[0]:
        out = escape(safety, pa, pb, safe_distance)
        if out is None:
            return None
        head, pa = [pa[None]], out
    if segment_safe(safety, pa, pb, safe_distance):
        return np.concatenate([*head, np.stack([pa, pb])])
    try:
        result = plan_path(safety, pa, pb, safety_distance=safe_distance, planner="RRTstar", time_limit_s=time_limit_s,
                           seed=seed, iterations=iterations)
    except ValueError:
        return None
    return np.concatenate([*head, result.points]) if result.solved else None


def escape(safety: ClearanceGrid, a: Array, toward: Array, safe_distance: float) -> Array | None:
    """The nearest valid point (up to three cells away, towards `toward` among equals) reachable from `a` by a
    straight segment that keeps `safe_distance` (`segment_safe`); None when there is none."""
    n = 96
    k = np.arange(n) + 0.5
    polar = np.arccos(1.0 - 2.0 * k / n)
    azimuth = math.pi * (1.0 + 5.0**0.5) * k
    dirs = np.stack([np.cos(azimuth) * np.sin(polar), np.sin(azimuth) * np.sin(polar), np.cos(polar)], axis=1)
    for radius in safety.cell * np.array([0.5, 1.0, 1.5, 2.0, 3.0]):
        ends = a + radius * dirs
        ends = ends[is_safe(safety, ends, safe_distance)]
        for end in ends[np.argsort(np.linalg.norm(ends - toward, axis=1))]:
            if segment_safe(safety, a, end, safe_distance):
                return np.asarray(end)
    return None


def run_exploration(planner: ViewPlanner, sense: Callable[[View], Scan], start: View, *, safe_distance: float,
                    budget_m: float = math.inf, max_views: int = 200,
                    coverage: Callable[[], float] | None = None, coverage_target: float = 1.0,
                    max_rejections: int = 20, seed: int | None = None) -> ExplorationLog:
    """Scan at `start`, then propose → connect → move → scan until a stopping rule fires."""
    log = ExplorationLog()
    t0 = time.perf_counter()
    planner.integrate(sense(start))
    log.steps.append(Step(start, start.point[None], 0.0, coverage() if coverage else None,
                          time.perf_counter() - t0, 0.0))
    pose, length, rejections = start, 0.0, 0
    while len(log.steps) < max_views:
        t0 = time.perf_counter()
        target = planner.propose(pose)
        plan_s = time.perf_counter() - t0
        if target is None:
            log.stop_reason = "nothing left to reveal"
            break
        t1 = time.perf_counter()
        path = connect(planner.safety, pose.point, target.point, safe_distance, seed=seed)
        connect_s = time.perf_counter() - t1
        if path is None:
            planner.reject(target)
            log.rejected += 1
            rejections += 1
            if rejections >= max_rejections:
                log.stop_reason = "no reachable view"
                break
            continue
        rejections = 0
        step_length = float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum())
        if length + step_length > budget_m:
            log.stop_reason = "budget"
            break
        length += step_length
        pose = target
        t2 = time.perf_counter()
        planner.integrate(sense(pose))
        plan_s += time.perf_counter() - t2
        cov = coverage() if coverage else None
        log.steps.append(Step(pose, path, length, cov, plan_s, connect_s))
        if cov is not None and cov >= coverage_target:
            log.stop_reason = "coverage target"
            break
    else:
        log.stop_reason = "view limit"
    return log


def explore(sense: Callable[[View], Scan], start: View, *, lo: ArrayLike, hi: ArrayLike, scanner: Scanner,
            weights: Weights | None = None, safe_distance: float = 5.0, budget_m: float = math.inf,
            coverage: Callable[[VoxelMap], float] | None = None, coverage_target: float = 0.9,
            resolution: float = 0.25, voxel_map_factory: Callable[[], VoxelMap] | None = None,
            candidates: int = 200, max_views: int = 200, seed: int | None = None) -> tuple[ExplorationLog,
                                                                                          NbvPlanner]:
    """Explore the box [lo, hi] from `start` with the seed's next-best-view planner; returns the log and planner.

    `sense(view)` returns the scan taken there; `coverage(voxel_map)` (optional, e.g. against ground truth in a
    simulation) stops the loop at `coverage_target`.
    """
    vmap = voxel_map_factory() if voxel_map_factory is not None else VoxelMap(resolution)
    planner = NbvPlanner(vmap, lo, hi, scanner, weights=weights or Weights(), safe_distance=safe_distance,
                         candidates=candidates, seed=seed)
    cov = (lambda: coverage(vmap)) if coverage is not None else None
    log = run_exploration(planner, sense, start, safe_distance=safe_distance, budget_m=budget_m,
                          max_views=max_views, coverage=cov, coverage_target=coverage_target, seed=seed)
    return log, planner
