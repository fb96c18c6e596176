"""Meander (boustrophedon) coverage of a survey area minus no-go zones (seed 002 §2.1): the vehicle's passes cover
the area with the fewest turns and the shortest path, its turns respect the turning radius, it keeps out of the
forbidden zones, and it starts and finishes near given points.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .baseline import best_single_direction_runs, single_direction_runs
from .heading import (
    edge_headings,
    heading_grid,
    merge_headings,
    row_statistics,
    shortlist,
    sweep_score,
    u_turn_length,
)
from .headlands import core_region, headland_tasks
from .plan import CoveragePlan, assemble, estimated_length
from .runs import Run
from .scene import QUAD, Scene
from .sweep import Passing, Sweep, SweepCache
from .tasks import Tasks, cell_tasks, order_tasks, trimmed, trimmed_rows, uncovered_area

Array = NDArray[np.float64]
# estimated length, sweep, runs in flying order, cells, method, whether its coverage must be checked
Option = tuple[float, Sweep, list[Run], int, str, bool]
SHORTLIST = 2
FULL_PLANS = 2         # line directions ordered in full
SMALL_AREA = 0.5e6     # m²: areas this small plan quickly, and try twice as many line directions
TINY_AREA = 0.12e6     # m²: areas this small also order two more drafts in full
ALTERNATIVE_AREA = 2.5e6   # m²: areas this small also try their lines without detours, and slid (larger ones
                           # take too long)
HEADLAND_PLANS = 1     # of which also planned in the headland layout
SLIVER, FINE_SLIVER = 1e-3, 1e-5   # parts of a band (in spacing²) a cut line may give up
INSET = 0.9            # share of the swath's overlap reach by which the outermost lines stand in
REACH = 0.5            # spacings by which a line may bend aside round a zone
PHASES = (0.0, 1.0)    # where the grid of lines is also slid to: either end of its slack (`build_sweep` phase)
SLID = 1               # most promising line directions also laid out with their grid slid (three over small areas)


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

    `spacing` is required (it has a default only so that it may follow `exclude` positionally). What the plan
    guarantees:

    - lines are at most `spacing` apart (shrunk so that a whole number fits), each long enough that a swath of
      `swath` (default: the spacing) covers its band; with a wider swath the outermost lines stand in from the
      boundary by most of the overlap;
    - no part of the path comes closer to a zone than half the `clearance`; lines turn no closer than the turning
      radius plus the clearance; turns are Dubins paths of radius `turn_radius` (U-turns when lines are at least
      2R apart, Ω-turns otherwise) and transits route round the zones;
    - passes along the zones' boundaries are added until at most `fill_tolerance` of the free area is left
      uncovered;
    - the path starts at the line end nearest `start` and prefers to finish near `finish`.

    How it is planned:

    1. Directions: with `heading="auto"`, the directions of the boundary edges and a 2° grid are scored in closed
       form (number of lines, then length: `heading.row_statistics`); the best `SHORTLIST` and the single-direction
       sweep's heading go on (twice as many over areas up to `SMALL_AREA`).
    2. Lines per direction (`sweep.build_sweep`): a line that passes a zone without crossing it runs on past it,
       slid sideways within its spare overlap or bent round it on Dubins ramps (up to `REACH` spacings); over
       areas up to `ALTERNATIVE_AREA` the lines without detours, and the most promising direction(s) with the
       grid slid to either end of its slack (`PHASES`, `SLID`), are drafted too.
    3. Cells: where zones or bays split the lines, the free area is decomposed into boustrophedon cells, each a
       meander; contour passes fill the strips next to the zones, and the lines are cut back to what those passes
       leave uncovered (`trims`), so that nothing is swept twice. A second layout flies a ring round every zone
       and lays lines over the rest only (`headlands`, for the best `HEADLAND_PLANS` direction).
    4. Order: the cells, their start corners and directions are ordered to minimise the transits plus the
       meanders as flown (`ordering.order_variants`: exact while small, else greedy tours refined by 2-opt and
       or-opt), for the `FULL_PLANS` best drafts (more over areas up to `TINY_AREA`).
    5. Choice: the best single-direction boustrophedon (`baseline_boustrophedon`) is planned too; every cell
       plan whose estimate is within 2 % of it is flown in full and the shortest no longer than it is returned;
       failing that, the single-direction sweep with its lines cut back ("single-direction-cut") if shorter, else
       the single-direction plan itself. `method` says which.

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
        base_sweep, base_runs = best_single_direction_runs(scene, sweeps, 1.0, fill_tolerance, s_xy)
        cands = merge_headings(heading_grid(2.0), edge_headings(scene.area, spacing / 2.0),
                               edge_headings(scene.zones, spacing / 2.0))
        lines, length, gaps = row_statistics(scene.region, cands, spacing)
        score = sweep_score(lines, length, gaps, u_turn_length(spacing, scene.radius))
        heads = merge_headings(shortlist(cands, (score, lines), SHORTLIST * _scale(scene)), [base_sweep.heading_deg])
    else:
        h = float(heading) % 180.0
        base_sweep = sweeps.get(h)
        base_runs = single_direction_runs(scene, base_sweep, fill_tolerance, s_xy)
        heads = np.array([h])
    base = _Cap(scene, base_sweep, base_runs)
    # every direction planned up to its tasks; the most promising trimmed and ordered in full, with lines up to the
    # zones and (the best) in the headland layout too
    # our lines: the outermost ones may stand in from the edge by what the swath's overlap covers
    inset = max(0.0, INSET * 0.5 * (scene.swath - spacing))
    passing = _passing(scene, spacing, inset)
    lined = _line_layouts(scene, spacing, inset, passing, heads)
    ranked = sorted((cell_tasks(scene, sw, fill_tolerance) for sw in lined), key=Tasks.rough_length)
    slid: list[Tasks] = []
    small = scene.area.area <= SMALL_AREA
    if scene.has_zones and ranked and scene.area.area <= ALTERNATIVE_AREA:
        count = 3 * SLID if small else SLID
        slid = [cell_tasks(scene, sw, fill_tolerance)
                for sw in _slid_layouts(scene, spacing, inset, passing, _directions(ranked, count))]
    # (draft, whether its coverage must be checked)
    layouts = _drafts(ranked, slid, _full_plans(scene), 1 if small else FULL_PLANS)
    drafts = [draft for draft, _ in layouts]
    rings = headland_tasks(scene)
    if rings and drafts:
        core = SweepCache(core_region(scene, [variants[0] for variants in rings]), scene.forbidden, spacing, inset,
                          passing)
        for draft in drafts[:HEADLAND_PLANS]:
            inner = core.get(draft.sweep.heading_deg)
            if inner.pieces:
                layouts.append((cell_tasks(scene, inner, fill_tolerance, rings), True))
    options: list[Option] = []
    for draft, check in layouts:
        tasks = trimmed(scene, draft, fill_tolerance)
        runs = order_tasks(scene, tasks.all, s_xy, f_xy)
        options.append((estimated_length(scene, runs), tasks.sweep, runs, len(tasks.cells), "boustrophedon-cells",
                        check))
    # the contour passes fill what the cells' lines leave to the tolerance; plans built otherwise (round rings, a
    # slid line grid, cut single-direction rows) may leave no more uncovered than the tolerance or, if that leaves
    # more, than the single-direction plan does
    def allowed() -> float:
        return float(max(fill_tolerance * scene.free.area, uncovered_area(scene, base_runs)) + 1e-6)

    plan = _shortest(scene, options, base, allowed)
    for neighbours, sliver in ((True, SLIVER), (False, SLIVER), (True, FINE_SLIVER), (False, FINE_SLIVER)):
        if plan is not None:
            break
        # no cell plan beats the single-direction sweep: that sweep with its lines cut back (the finer cuts keep
        # the small parts of the bands, at the corners of the contour passes, that the coarser ones give up)
        rows = trimmed_rows(scene, base_sweep, base_runs, fill_tolerance, s_xy, neighbours, sliver)
        if rows is not None:
            plan = _shortest(scene, [(estimated_length(scene, rows), base_sweep, rows, 1, "single-direction-cut",
                                      True)], base, allowed)
    return base.plan if plan is None else plan


class _Cap:
    """The single-direction plan that ours may not be longer than, built only when a comparison needs its length:
    its runs plus straight hops between them are a lower bound (a transit is no shorter than the straight line),
    and most of our plans are shorter than that."""

    def __init__(self, scene: Scene, sweep: Sweep, runs: list[Run]):
        self.scene, self.sweep, self.runs = scene, sweep, runs
        hops = sum(float(np.linalg.norm(b.path[0] - a.path[-1])) for a, b in zip(runs[:-1], runs[1:], strict=True))
        self.lower = (sum(r.length for r in runs) + hops) * (1.0 - 1e-9)
        self._plan: CoveragePlan | None = None

    @property
    def plan(self) -> CoveragePlan:
        if self._plan is None:
            self._plan = assemble(self.scene, self.runs, self.sweep.heading_deg, self.sweep.spacing, 1,
                                  "single-direction")
        return self._plan

    def below(self, length: float, factor: float = 1.0, slack: float = 0.0) -> bool:
        """Whether `length` ≤ `factor` times the plan's length plus `slack`."""
        return length <= factor * self.lower + slack or length <= factor * self.plan.length_m + slack


def _passing(scene: Scene, spacing: float, inset: float) -> Passing | None:
    """How our lines may pass the zones: they run on past a zone they only graze (the clearance kept: no turn is
    made there), slide sideways by up to the inset (their band stays covered) or bend round it by up to `REACH`
    spacings to do so."""
    if not scene.has_zones:
        return None
    return Passing(scene.zones.buffer(scene.clearance, quad_segs=QUAD), inset, REACH * spacing, scene.radius)


def _line_layouts(scene: Scene, spacing: float, inset: float, passing: Passing | None, heads: Array) -> list[Sweep]:
    """The distinct sweeps to plan up to their tasks: per heading, the lines passing the zones as `passing` lets
    them; over areas up to `ALTERNATIVE_AREA` (quick enough to plan) also without detours, since bending round a
    zone does not always give the better cells."""
    caches = [SweepCache(scene.region, scene.forbidden, spacing, inset, passing)]
    if scene.area.area <= ALTERNATIVE_AREA:
        straight = None if passing is None else Passing(passing.blocking, passing.shift)
        caches.append(SweepCache(scene.region, scene.forbidden, spacing, inset, straight))
    out: list[Sweep] = []
    for h in heads:
        for cache in caches:
            sweep = cache.get(float(h))
            if sweep.pieces and all(sweep.pieces != other.pieces for other in out):
                out.append(sweep)
    return out


def _slid_layouts(scene: Scene, spacing: float, inset: float, passing: Passing | None,
                  sweeps: Sequence[Sweep]) -> list[Sweep]:
    """The directions of `sweeps` with their rows a full spacing apart and the grid slid to either end of its
    slack (`PHASES`, see `build_sweep`): a zone that falls between two lines splits none. Only those differing
    from `sweeps` and from each other."""
    out: list[Sweep] = []
    for phase in PHASES:
        cache = SweepCache(scene.region, scene.forbidden, spacing, inset, passing, phase)
        for sweep in sweeps:
            slid = cache.get(sweep.heading_deg)
            if slid.pieces and all(slid.pieces != other.pieces for other in [*sweeps, *out]):
                out.append(slid)
    return out


def _directions(ranked: list[Tasks], count: int) -> list[Sweep]:
    """The sweeps of the first `count` distinct line directions among the `ranked` drafts."""
    out: list[Sweep] = []
    for draft in ranked:
        if len(out) == count:
            break
        if all(abs(draft.sweep.heading_deg - other.heading_deg) > 1e-9 for other in out):
            out.append(draft.sweep)
    return out


def _drafts(ranked: list[Tasks], slid: list[Tasks], count: int, kept: int) -> list[tuple[Tasks, bool]]:
    """The `count` drafts of least rough length among the `ranked` ones (sorted) and the `slid` ones, each with
    whether it is slid, plus any of the best `kept` ranked ones they displace: a rough length misjudges the cut
    lines and the order, and a slid grid that looks better need not be.

    >>> from types import SimpleNamespace as Draft
    >>> a, b, c, d = (Draft(rough_length=lambda x=x: x) for x in (1.0, 2.0, 3.0, 1.5))
    >>> [(t.rough_length(), s) for t, s in _drafts([a, b, c], [d], 2, 2)]      # d displaces b, which is kept
    [(1.0, False), (1.5, True), (2.0, False)]
    >>> [(t.rough_length(), s) for t, s in _drafts([a, b, c], [d], 2, 1)]
    [(1.0, False), (1.5, True)]
    """
    pool = sorted([(d, False) for d in ranked] + [(d, True) for d in slid], key=lambda t: t[0].rough_length())
    top = pool[:count]
    return top + [(d, False) for d in ranked[:kept] if all(d is not other for other, _ in top)]


def _full_plans(scene: Scene) -> int:
    """How many drafts to cut back and order in full: `FULL_PLANS`, twice as many over small areas and two more
    over tiny ones (quick to plan)."""
    return FULL_PLANS * _scale(scene) + (2 if scene.area.area <= TINY_AREA else 0)


def _scale(scene: Scene) -> int:
    """How many times the usual number of line directions to try: twice over small areas."""
    return 2 if scene.area.area <= SMALL_AREA else 1


def _shortest(scene: Scene, options: list[Option], base: _Cap,
              allowed: Callable[[], float]) -> CoveragePlan | None:
    """The shortest option flown in full that is no longer than `base` (and, where it is to be checked, leaves at
    most `allowed()` m² of the free area uncovered). Estimates only screen the options: every one within 2 % of
    `base` and below the shortest flown so far is flown in full, since the transits as built may differ from
    their estimates either way."""
    best: CoveragePlan | None = None
    for estimate, sweep, runs, n_cells, method, check in sorted(options, key=lambda o: o[0]):
        if not base.below(estimate, 1.02) or (best is not None and estimate >= best.length_m):
            continue
        if check and uncovered_area(scene, runs) > allowed():
            continue
        plan = assemble(scene, runs, sweep.heading_deg, sweep.spacing, n_cells, method)
        if base.below(plan.length_m, slack=1e-6) and (best is None or plan.length_m < best.length_m):
            best = plan
    return best
