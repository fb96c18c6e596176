"""The tasks of a cell plan for one line direction (seed 002 §2.1): the boustrophedon cells' meanders, the passes
round the zones, and their order.

A task is flown by exactly one of its variants (start side, direction, entry point). The cells come from the
sweep's decomposition; the headland rings (if any) and the contour passes the lines leave needed are added
(`cell_tasks`); the lines are then cut back to what those passes leave uncovered, and the cells re-planned on the
cut lines when that keeps the coverage (`trimmed`). The order of the tasks and their variants minimises the
transits (`order_tasks`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely
from numpy.typing import NDArray
from shapely.geometry.base import BaseGeometry

from .baseline import single_direction_runs
from .cells import cell_variants, decompose
from .contours import contour_runs
from .frames import from_sweep, to_sweep
from .joins import Joiner
from .metrics import swept, uncovered
from .ordering import order_variants
from .runs import Run
from .scene import Scene
from .sweep import Piece, Sweep
from .trims import trim_to_need, trim_to_neighbours

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Tasks:
    """The tasks of one line direction: each a list of variants (runs in (forward, backward) pairs)."""

    sweep: Sweep
    cells: list[list[Run]]          # the cells' meanders
    extra: list[list[Run]]          # headland rings and contour passes

    @property
    def all(self) -> list[list[Run]]:
        return self.cells + self.extra

    def rough_length(self) -> float:
        """The tasks' own lengths (the shortest variant of each) plus a spacing per transit: a cheap score to
        choose which line directions to order in full."""
        tasks = self.all
        return sum(min(r.length for r in v) for v in tasks) + self.sweep.spacing * max(len(tasks) - 1, 0)


def cell_tasks(scene: Scene, sweep: Sweep, tolerance: float, rings: Sequence[list[Run]] = ()) -> Tasks:
    """The cells of `sweep`, the headland `rings`, and the contour passes needed so that at most `tolerance` of the
    free area is left uncovered."""
    if not sweep.pieces:
        raise ValueError("no survey line fits in the area outside the no-go zones")
    cells = cell_variants(Joiner(scene, sweep), decompose(sweep))
    if not scene.has_zones:
        return Tasks(sweep, cells, [])
    # what the lines cover whichever start side each cell is flown from (turns may pull line ends back)
    flown = common_lines(cells, sweep.heading_deg) + [seg for variants in rings for seg in variants[0].lines]
    residual = scene.free.difference(swept(flown, scene.swath))
    extra = [list(variants) for variants in rings]
    # each stretch of ring needed is a task of its own: the ordering flies from one to the next where that is
    # shortest, rather than along the ring between them
    extra += [[c, c.reversed()] for c in contour_runs(scene, residual, sweep.spacing, tolerance, 0.0)]
    return Tasks(sweep, cells, extra)


def order_tasks(scene: Scene, tasks: Sequence[list[Run]], start: Array | None = None,
                finish: Array | None = None) -> list[Run]:
    """One variant of every task, in flying order, minimising the transits plus the approach from `start` and the
    way to `finish` (x, y), plus the variants' own lengths (a cell's meanders from either side differ in their
    turns and line ends: each counts half on the way in, half on the way out)."""
    runs: list[Run] = [r for variants in tasks for r in variants]
    task_of = np.array([t for t, variants in enumerate(tasks) for _ in variants], dtype=np.int64)
    reverse_of = np.arange(len(runs), dtype=np.int64) ^ 1           # variants come in (forward, backward) pairs
    entries = np.array([r.path[0] for r in runs])
    exits = np.array([r.path[-1] for r in runs])
    cost = scene.transit_costs(exits, np.array([r.exit_angle for r in runs]), entries,
                               np.array([r.entry_angle for r in runs]))
    cost[task_of[:, None] == task_of[None, :]] = np.inf
    start_cost = np.zeros(len(runs)) if start is None else _reachable(
        scene.router.lengths(start, entries)[0], np.linalg.norm(entries - start, axis=1))
    finish_cost = np.zeros(len(runs)) if finish is None else _reachable(
        scene.router.lengths(exits, finish)[:, 0], np.linalg.norm(exits - finish, axis=1))
    half = 0.5 * np.array([r.length for r in runs])
    order = order_variants(task_of, reverse_of, cost + half[:, None] + half[None, :], start_cost + half,
                           finish_cost + half)
    return [runs[v] for v in order]


def _reachable(routed: Array, direct: Array) -> Array:
    """Route lengths with a large finite cost where no route round the zones exists (a start or finish point shut
    in by zones), so that the order stays well defined."""
    return np.where(np.isfinite(routed), routed, 10.0 * direct + 1e6)


def uncovered_area(scene: Scene, runs: Sequence[Run]) -> float:
    """The free area the passes of `runs` leave uncovered (m²)."""
    return float(uncovered([seg for run in runs for seg in run.lines], scene.free, scene.swath).area)


def trimmed(scene: Scene, plan: Tasks, tolerance: float) -> Tasks:
    """The cells re-planned with their lines cut back to what the other passes leave uncovered and then to what
    the neighbouring lines' swaths leave of their bands; failing that, cut back to the other passes only; failing
    that too, as they were. Contour passes are added for what the (re-planned) lines leave uncovered beyond the
    tolerance (turns next to zones may pull line ends back); a cut is kept if at most `tolerance` of the free
    area, or no more than the uncut lines left, stays uncovered."""
    sweep = plan.sweep
    others = [seg for variants in plan.extra for seg in variants[0].lines]
    budget = tolerance * scene.free.area + 1e-6
    try:
        covered = swept(others, scene.swath) if others else None
        need = scene.free if covered is None else scene.free.difference(covered)
        first = sweep if covered is None else trim_to_need(sweep, need, covered)
        second = trim_to_neighbours(first, need, scene.swath)
    except shapely.errors.GEOSException:          # cutting is an optimisation: a topology failure keeps the lines
        second = first = sweep
        need = scene.free

    def gap(cells: list[list[Run]]) -> BaseGeometry:
        return need.difference(swept(common_lines(cells, sweep.heading_deg), scene.swath))

    uncut: float | None = None
    tried: list[tuple[Piece, ...]] = []
    for cut in (second, first, sweep):
        if cut.pieces in tried or not cut.pieces:
            continue
        tried.append(cut.pieces)
        cells = plan.cells if cut is sweep else cell_variants(Joiner(scene, cut), decompose(cut))
        left = gap(cells)
        extra = plan.extra
        if left.area > budget and scene.has_zones:
            top = contour_runs(scene, left, sweep.spacing, tolerance, 0.0)
            if top:
                left = left.difference(swept([seg for run in top for seg in run.lines], scene.swath))
                extra = extra + [[run, run.reversed()] for run in top]
        if cut is not sweep and left.area > budget:
            uncut = gap(plan.cells).area if uncut is None else uncut
            if left.area > uncut + 1e-6:
                continue
        return Tasks(cut, cells, extra)
    return plan


def trimmed_rows(scene: Scene, sweep: Sweep, runs: Sequence[Run], tolerance: float, start: Array | None = None,
                 neighbours: bool = True, sliver: float = 1e-3) -> list[Run] | None:
    """The single-direction sweep `runs` (rows in order, see `single_direction_runs`) with the lines cut back to
    what its contour passes (and with `neighbours`, the neighbouring lines) leave uncovered, ignoring parts of a
    band smaller than `sliver`·spacing²: the runs in flying order, contour passes inserted; None if no line can be
    cut."""
    passes = [seg for run in runs if run.turns == 0 and len(run.path) > 2 for seg in run.lines]
    try:
        covered = swept(passes, scene.swath) if passes else None
        need = scene.free if covered is None else scene.free.difference(covered)
        cut = sweep if covered is None else trim_to_need(sweep, need, covered, sliver)
        if neighbours:
            cut = trim_to_neighbours(cut, need, scene.swath, sliver)
    except shapely.errors.GEOSException:
        return None
    if cut.pieces == sweep.pieces or not cut.pieces:
        return None
    return single_direction_runs(scene, cut, tolerance, start)


def common_lines(tasks: list[list[Run]], heading_deg: float) -> list[Array]:
    """Each cell's lines shortened to the part every variant of the cell flies.

    The variants fly the same lines, some the other way round and some pulled back at their ends: the passes of
    each are matched up as sweep-frame segments running along +u, in order of their ends' v and then along u (a
    detour's straights, which every variant flies alike, match exactly)."""
    out: list[Array] = []
    for variants in tasks:
        legs = [_sweep_legs(run, heading_deg) for run in variants[0::2]]
        if any(len(other) != len(legs[0]) for other in legs[1:]):      # an end pulled back to nothing: only the
            out.extend(from_sweep(seg, heading_deg) for seg in legs[0]  # passes all variants fly alike are sure
                       if all(any(np.array_equal(seg, o) for o in other) for other in legs[1:]))
            continue
        for group in zip(*legs, strict=True):
            first = group[0]
            if all(np.array_equal(seg, first) for seg in group[1:]):
                out.append(from_sweep(first, heading_deg))
                continue
            lo = max(float(seg[0, 0]) for seg in group)
            hi = min(float(seg[1, 0]) for seg in group)
            if hi > lo:
                out.append(from_sweep(np.array([[lo, first[0, 1]], [hi, first[0, 1]]]), heading_deg))
    return out


def _sweep_legs(run: Run, heading_deg: float) -> list[Array]:
    """The passes of `run` in the sweep frame, each running along +u, ordered by the v of its ends, then by u."""
    legs = [to_sweep(seg, heading_deg) for seg in run.lines]
    legs = [seg[::-1] if seg[1, 0] < seg[0, 0] else seg for seg in legs]
    return sorted(legs, key=lambda seg: (round(float(seg[0, 1]), 6), round(float(seg[1, 1]), 6),
                                         float(seg[:, 0].mean())))
