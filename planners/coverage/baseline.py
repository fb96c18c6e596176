"""The benchmark anchor (seed 002 §2.1): a single-direction boustrophedon over the whole area with a brute-force
search of the line angle — the default of Fields2Cover (BruteForce swath generator + Boustrophedon route +
Dubins turns), which does not install offline and is re-implemented here.

Lines are the same as the cell planner's (one per band slice, clipped by the no-go zones); they are flown row by
row in sweep order, a row split by a zone becoming several segments visited along the row with transits around
the zone; turns and transits are the same Dubins/visibility-graph manoeuvres, and the same contour passes fill
what the lines leave uncovered next to the zones (inserted where they cost least), so that both planners are
compared at the same coverage. Every angle is scored in closed form; the best few are planned in full and the
shortest path wins.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .contours import contour_runs
from .heading import heading_grid, row_statistics, shortlist, sweep_score, u_turn_length
from .joins import Joiner
from .metrics import uncovered
from .plan import CoveragePlan, assemble, estimated_length
from .runs import Run
from .scene import Scene
from .sweep import Sweep, SweepCache

Array = NDArray[np.float64]
SHORTLIST = 5


def baseline_boustrophedon(
    area: ArrayLike,
    exclude: Sequence[ArrayLike],
    spacing: float,
    turn_radius: float = 0.0,
    angle_step_deg: float = 1.0,
    *,
    swath: float | None = None,
    clearance: float = 2.0,
    fill_tolerance: float = 1e-3,
) -> CoveragePlan:
    """The shortest single-direction boustrophedon over `area` minus `exclude` ([north, east] metres).

    Angles 0, step, 2·step … below 180° are scored in closed form; the `SHORTLIST` best are planned (lines,
    turns, contour passes, transit lengths) and the shortest is returned (`method` "single-direction", `cells`
    1). `swath`, `clearance` and `fill_tolerance` are as in `meander`.

    >>> plan = baseline_boustrophedon([[0, 0], [0, 400], [100, 400], [100, 0]], [], 25.0)
    >>> plan.heading_deg, len(plan.lines), plan.turns
    (90.0, 4, 3)
    """
    if spacing <= 0.0:
        raise ValueError(f"spacing must be positive, got {spacing}")
    scene = Scene.build(area, exclude, turn_radius, clearance, swath or spacing)
    sweeps = SweepCache(scene.region, scene.forbidden, spacing)
    return best_single_direction(scene, sweeps, angle_step_deg, fill_tolerance)


def best_single_direction(scene: Scene, sweeps: SweepCache, angle_step_deg: float, tolerance: float,
                          start: Array | None = None) -> CoveragePlan:
    sweep, runs = best_single_direction_runs(scene, sweeps, angle_step_deg, tolerance, start)
    return assemble(scene, runs, sweep.heading_deg, sweep.spacing, 1, "single-direction")


def best_single_direction_runs(scene: Scene, sweeps: SweepCache, angle_step_deg: float, tolerance: float,
                               start: Array | None = None) -> tuple[Sweep, list[Run]]:
    """The sweep and runs of `best_single_direction`, not yet joined by transits."""
    headings = heading_grid(angle_step_deg)
    lines, length, gaps = row_statistics(scene.region, headings, sweeps.spacing)
    score = sweep_score(lines, length, gaps, u_turn_length(sweeps.spacing, scene.radius))
    top = shortlist(headings, (score,), SHORTLIST)
    options = [(sweeps.get(float(h)), single_direction_runs(scene, sweeps.get(float(h)), tolerance, start))
               for h in top]
    return min(options, key=lambda o: estimated_length(scene, o[1]))


def single_direction_plan(scene: Scene, sweep: Sweep, tolerance: float, start: Array | None = None) -> CoveragePlan:
    """Rows flown in sweep order, alternating direction, starting at the corner nearest `start` (x, y)."""
    runs = single_direction_runs(scene, sweep, tolerance, start)
    return assemble(scene, runs, sweep.heading_deg, sweep.spacing, 1, "single-direction")


def single_direction_runs(scene: Scene, sweep: Sweep, tolerance: float, start: Array | None = None) -> list[Run]:
    """The runs of `single_direction_plan`, contour passes inserted, not yet joined by transits."""
    by_row: dict[int, list[int]] = {}
    for pid, p in enumerate(sweep.pieces):
        by_row.setdefault(p.row, []).append(pid)
    rows = sorted(by_row)
    if not rows:
        raise ValueError("no survey line fits in the area outside the no-go zones")
    best: tuple[float, list[tuple[int, int]]] | None = None
    for order in (rows, rows[::-1]):
        for d0 in (1, -1):
            items: list[tuple[int, int]] = []
            d = d0
            for r in order:
                ids = sorted(by_row[r], key=lambda k: sweep.pieces[k].u0)
                items.extend((k, d) for k in (ids if d > 0 else ids[::-1]))
                d = -d
            p = sweep.pieces[items[0][0]]
            first = sweep.points(np.array([p.u0 if items[0][1] > 0 else p.u1]), np.array([p.v]))[0]
            dist = 0.0 if start is None else float(np.linalg.norm(first - start))
            if best is None or dist < best[0] - 1e-9:
                best = (dist, items)
    assert best is not None
    joiner = Joiner(scene, sweep)
    runs = joiner.sequence(best[1])
    lines = [seg for run in runs for seg in run.lines]
    extra = contour_runs(scene, uncovered(lines, scene.free, scene.swath), sweep.spacing, tolerance)
    return insert_cheapest(scene, runs, extra)


def insert_cheapest(scene: Scene, runs: list[Run], extra: list[Run]) -> list[Run]:
    """Insert each extra run (either way round) between the runs, or at an end, where it adds the least transit.

    Positions are chosen against the original sequence; runs choosing the same gap are flown in turn there.
    """
    if not extra:
        return list(runs)
    options = [o for run in extra for o in (run, run.reversed())]
    exits = np.array([r.path[-1] for r in runs])
    exit_a = np.array([r.exit_angle for r in runs])
    entries = np.array([r.path[0] for r in runs])
    entry_a = np.array([r.entry_angle for r in runs])
    to_opt = scene.transit_costs(exits, exit_a, np.array([o.path[0] for o in options]),
                                 np.array([o.entry_angle for o in options]))              # (N, 2E)
    from_opt = scene.transit_costs(np.array([o.path[-1] for o in options]), np.array([o.exit_angle for o in options]),
                                   entries, entry_a)                                      # (2E, N)
    link = scene.pair_costs(exits[:-1], exit_a[:-1], entries[1:], entry_a[1:])           # (N - 1,)
    n = len(runs)
    add = np.zeros((len(options), n + 1))
    add[:, 1:] += to_opt.T
    add[:, :-1] += from_opt
    add[:, 1:-1] -= link[None, :]
    slots: list[list[Run]] = [[] for _ in range(n + 1)]
    for k in range(len(extra)):
        pair = add[2 * k : 2 * k + 2]
        o, pos = divmod(int(np.argmin(pair)), n + 1)
        slots[pos].append(options[2 * k + o])
    out: list[Run] = []
    for pos in range(n + 1):
        out.extend(slots[pos])
        if pos < n:
            out.append(runs[pos])
    return out
