"""Meander (boustrophedon) coverage of a survey area minus no-go zones (seed 002 §2.1): the vehicle's passes cover
the area with the fewest turns and the shortest path, its turns respect the turning radius, it keeps out of the
forbidden zones, and it starts and finishes near given points.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .baseline import best_single_direction, single_direction_plan
from .cells import cell_variants, decompose
from .contours import contour_runs
from .frames import from_sweep, to_sweep
from .heading import (
    edge_headings,
    heading_grid,
    merge_headings,
    row_statistics,
    shortlist,
    sweep_score,
    u_turn_length,
)
from .joins import Joiner
from .metrics import swept
from .ordering import order_variants
from .plan import CoveragePlan, assemble, count_turns, estimated_length
from .runs import Run
from .scene import Scene
from .sweep import Sweep, SweepCache

Array = NDArray[np.float64]
SHORTLIST = 4


def meander(
    area: ArrayLike,
    exclude: Sequence[ArrayLike] = (),
    spacing: float | None = None,
    heading: float | Literal["auto"] = "auto",
    turn_radius: float = 0.0,
    start: ArrayLike | None = None,
    finish: ArrayLike | None = None,
    *,
    swath: float | None = None,
    clearance: float = 2.0,
    fill_tolerance: float = 1e-3,
) -> CoveragePlan:
    """Boustrophedon coverage of `area` minus the `exclude` polygons ([north, east] metres).

    `spacing` is required (it has a default only so that it may follow `exclude` positionally). Lines are
    `spacing` apart at most (the spacing is shrunk so that a whole number of lines fits), each long
    enough that a swath of `spacing` covers its band; they stop short of the no-go zones by the turning radius
    plus `clearance`, and no part of the path comes closer to a zone than half the clearance. Where no-go zones
    (or bays of the boundary) split the lines, the free area is decomposed into boustrophedon cells, each flown
    as its own meander, and the cells, their start corners and directions are ordered to minimise the transits
    (exactly for up to 13 cells and contour passes, greedy + 2-opt + or-opt beyond); transits route round the
    zones. Turns are Dubins paths
    of radius `turn_radius`: U-turns when lines are at least 2R apart, Ω-turns otherwise. Passes along the zones'
    boundaries are added where the lines leave more than `fill_tolerance` of the free area uncovered by a swath
    of `swath` (default: the spacing). The path starts at the line end nearest `start` and prefers to finish
    near `finish`.

    `heading="auto"` tries the directions of the boundary edges and a 2° grid, scores them in closed form by
    number of lines (turns) and then length, and plans the best few in full. The best single-direction
    boustrophedon (`baseline_boustrophedon`) is planned too: the cell plan with the fewest turns, then the
    shortest, among those no longer than it is returned; if none is, the single-direction plan is returned
    (`method` tells which).

    >>> plan = meander([[0, 0], [0, 400], [100, 400], [100, 0]], spacing=25.0, turn_radius=5.0)
    >>> plan.heading_deg, len(plan.lines), plan.turns, plan.cells
    (90.0, 4, 3, 1)
    """
    if spacing is None:
        raise TypeError("meander() needs the line spacing")
    if spacing <= 0.0:
        raise ValueError(f"spacing must be positive, got {spacing}")
    scene = Scene.build(area, exclude, turn_radius, clearance, swath or spacing)
    sweeps = SweepCache(scene.region, scene.forbidden, spacing)
    s_xy = None if start is None else np.asarray(start, dtype=float).reshape(2)[::-1].copy()
    f_xy = None if finish is None else np.asarray(finish, dtype=float).reshape(2)[::-1].copy()
    if heading == "auto":
        base = best_single_direction(scene, sweeps, 1.0, fill_tolerance, s_xy)
        cands = merge_headings(heading_grid(2.0), edge_headings(scene.area, spacing / 2.0),
                               edge_headings(scene.zones, spacing / 2.0))
        lines, length, gaps = row_statistics(scene.region, cands, spacing)
        score = sweep_score(lines, length, gaps, u_turn_length(spacing, scene.radius))
        heads = merge_headings(shortlist(cands, (score, lines), SHORTLIST), [base.heading_deg])
    else:
        h = float(heading) % 180.0
        base = single_direction_plan(scene, sweeps.get(h), fill_tolerance, s_xy)
        heads = np.array([h])
    options = [(sweeps.get(float(h)), *cell_runs(scene, sweeps.get(float(h)), fill_tolerance, s_xy, f_xy))
               for h in heads]
    ranked = sorted(options, key=lambda o: (count_turns(o[1]), estimated_length(scene, o[1])))
    for sweep, runs, n_cells in ranked:
        if estimated_length(scene, runs) > base.length_m * 1.02:
            continue
        plan = assemble(scene, runs, sweep.heading_deg, sweep.spacing, n_cells, "boustrophedon-cells")
        if plan.length_m <= base.length_m + 1e-6:
            return plan
    return base


def cell_runs(scene: Scene, sweep: Sweep, tolerance: float, start: Array | None = None,
              finish: Array | None = None) -> tuple[list[Run], int]:
    """Boustrophedon cells of one sweep, each a meander, plus the contour passes the lines leave needed, ordered to
    minimise the transits: the runs in flying order (not yet joined by transits) and the number of cells."""
    if not sweep.pieces:
        raise ValueError("no survey line fits in the area outside the no-go zones")
    joiner = Joiner(scene, sweep)
    tasks = cell_variants(joiner, decompose(sweep))
    n_cells = len(tasks)
    if scene.has_zones:
        # what the lines cover whichever start side each cell is flown from (turns may pull line ends back)
        residual = scene.free.difference(swept(_common_lines(tasks, sweep.heading_deg), scene.swath))
        tasks += [[c, c.reversed()] for c in contour_runs(scene, residual, sweep.spacing, tolerance)]
    runs: list[Run] = [r for variants in tasks for r in variants]
    task_of = np.array([t for t, variants in enumerate(tasks) for _ in variants], dtype=np.int64)
    reverse_of = np.arange(len(runs), dtype=np.int64) ^ 1           # variants come in (forward, backward) pairs
    entries = np.array([r.path[0] for r in runs])
    exits = np.array([r.path[-1] for r in runs])
    cost = scene.transit_costs(exits, np.array([r.exit_angle for r in runs]), entries,
                               np.array([r.entry_angle for r in runs]))
    cost[task_of[:, None] == task_of[None, :]] = np.inf
    start_cost = np.zeros(len(runs)) if start is None else scene.router.lengths(start, entries)[0]
    finish_cost = np.zeros(len(runs)) if finish is None else scene.router.lengths(exits, finish)[:, 0]
    order = order_variants(task_of, reverse_of, cost, start_cost, finish_cost)
    return [runs[v] for v in order], n_cells


def _common_lines(tasks: list[list[Run]], heading_deg: float) -> list[Array]:
    """Each cell's lines shortened to the part every variant of the cell flies."""
    out = []
    for variants in tasks:
        forward = variants[0::2]
        for j in range(len(forward[0].lines)):
            uv = [to_sweep(run.lines[j], heading_deg) for run in forward]
            lo = max(float(seg[:, 0].min()) for seg in uv)
            hi = min(float(seg[:, 0].max()) for seg in uv)
            if hi > lo:
                out.append(from_sweep(np.array([[lo, uv[0][0, 1]], [hi, uv[0][0, 1]]]), heading_deg))
    return out
