"""Cell plans round no-go zones (seed 002 §2.1): lines cut back where contour passes already cover their band,
passes round the zones (headlands), the order of the tasks, and coverage of areas with holes."""

import numpy as np
import shapely
from shapely.geometry import LineString, Polygon, box
from turning import circumradii

from planners.coverage import baseline_boustrophedon, coverage_fraction, meander
from planners.coverage.baseline import single_direction_runs
from planners.coverage.headlands import core_region, headland_rings, headland_tasks
from planners.coverage.metrics import swept
from planners.coverage.ordering import order_variants, tour_cost
from planners.coverage.planner import _full_plans
from planners.coverage.runs import Run
from planners.coverage.scene import Scene
from planners.coverage.sweep import build_sweep
from planners.coverage.tasks import cell_tasks, common_lines, order_tasks, trimmed, trimmed_rows
from planners.coverage.trims import trim_to_need, trim_to_neighbours

SPACING = 50.0
SWATH = SPACING / 0.8                                       # 20 % overlap
WIDE = [[0, 0], [0, 1200], [600, 1200], [600, 0]]           # 600 m north × 1200 m east
BLOCK = [[150, 400], [150, 800], [450, 800], [450, 400]]    # splits the middle six east-west lines


def xy(poly):
    return Polygon([(e, n) for n, e in poly])


def test_a_line_whose_band_another_pass_covers_is_cut_back_or_dropped():
    sweep = build_sweep(box(0, 0, 400, 150), Polygon(), 90.0, 50.0)             # three rows of lines running east
    need = box(0, 0, 250, 50).union(box(0, 100, 400, 150))                       # row 0 half covered, row 1 covered
    cut = trim_to_need(sweep, need)
    assert [(p.row, round(p.u0), round(p.u1)) for p in cut.pieces] == [(0, 0, 250), (2, 0, 400)]
    assert cut.links == ()                                                        # rows 0 and 2 never touched


def test_a_band_tip_under_the_next_line_s_swath_is_left_to_that_line():
    # sides slanting at cot = 2/3 across six eastward rows: each row but the outermost gives up the tip at either
    # end that the row beyond covers, 0.95 of the overlap reach (swath - spacing)/2 = 6.25 m deep
    shape = Polygon([(0, 0), (500, 0), (700, 300), (200, 300)])
    sweep = build_sweep(shape, Polygon(), 90.0, SPACING)
    cut = trim_to_neighbours(sweep, shape, SWATH)
    saved = sum(p.length for p in sweep.pieces) - sum(p.length for p in cut.pieces)
    assert abs(saved - 10 * 0.95 * 6.25 * 2 / 3) < 0.5
    lines = [sweep.points(np.array([p.u0, p.u1]), np.array([p.v, p.v])) for p in cut.pieces]
    assert shape.difference(swept(lines, SWATH)).area < 1e-6 * shape.area


def test_lines_next_to_the_contour_passes_are_shortened_and_the_area_stays_covered():
    scene = Scene.build(WIDE, [BLOCK], 6.0, 2.0, SWATH)
    sweep = build_sweep(scene.region, scene.forbidden, 90.0, SPACING)
    full = cell_tasks(scene, sweep, 1e-3)
    cut = trimmed(scene, full, 1e-3)

    def line_length(tasks):
        return sum(float(np.linalg.norm(s[1] - s[0])) for s in common_lines(tasks.cells, 90.0))

    # the passes along the zone's west and east sides cover half a swath beyond the standoff; the twelve line ends
    # next to them give up most of it
    assert line_length(full) - line_length(cut) > 12 * 0.3 * SWATH
    passes = common_lines(cut.cells, 90.0) + [s for variants in cut.extra for s in variants[0].lines]
    assert scene.free.difference(swept(passes, SWATH)).area <= 1e-3 * scene.free.area + 1e-6


def test_the_single_direction_sweep_cut_back_next_to_its_contour_passes_is_shorter_and_as_well_covered():
    scene = Scene.build(WIDE, [BLOCK], 6.0, 2.0, SWATH)
    sweep = build_sweep(scene.region, scene.forbidden, 0.0, SPACING)              # north-south lines
    rows = single_direction_runs(scene, sweep, 1e-3)
    cut = trimmed_rows(scene, sweep, rows, 1e-3)
    assert cut is not None

    def passes(runs):
        return [s for run in runs for s in run.lines]

    def length(runs):
        return sum(float(np.linalg.norm(s[1] - s[0])) for s in passes(runs))

    assert length(cut) < length(rows) - 16 * 0.3 * SWATH      # the ends of the eight lines the block splits
    assert scene.free.difference(swept(passes(cut), SWATH)).area <= 1e-3 * scene.free.area + 1e-6


def test_headland_rings_keep_the_standoff_and_turn_no_tighter_than_the_radius():
    zones = [BLOCK, [[60, 100], [60, 200], [120, 150]]]
    scene = Scene.build(WIDE, zones, 6.0, 2.0, SWATH)
    rings = headland_rings(scene)
    assert len(rings) == 2
    for ring in rings:
        assert shapely.distance(LineString(ring), scene.zones) >= scene.standoff - 0.5
        assert circumradii(ring).min() >= 0.95 * 6.0
    core = core_region(scene, [variants[0] for variants in headland_tasks(scene)])
    # the ring's passes, at the standoff, cover 0.4 swath beyond it (the core reaches 0.1 swath under them)
    assert [core.contains(shapely.Point(600, 150 - d)) for d in (scene.standoff + 0.35 * SWATH, 50.0)] == [
        False, True]


def test_cells_beat_the_single_direction_sweep_where_a_zone_splits_the_lines():
    # the single-direction sweep flies six east-west lines that the block splits, each with a detour round the block
    # or a double back; the cells fly the strips north and south and the sides west and east as their own meanders
    plan = meander(WIDE, [BLOCK], spacing=SPACING, turn_radius=6.0, swath=SWATH)
    base = baseline_boustrophedon(WIDE, [BLOCK], SPACING, 6.0, swath=SWATH)
    assert plan.method == "boustrophedon-cells" and plan.cells >= 4
    assert plan.length_m <= 0.88 * base.length_m
    assert coverage_fraction(plan, WIDE, [BLOCK], SWATH) >= 0.999


def test_an_area_with_several_holes_is_covered_and_no_hole_is_entered():
    u_shape = [[0, 0], [0, 900], [700, 900], [700, 600], [250, 600], [250, 300], [700, 300], [700, 0]]
    holes = [[[60, 80], [60, 200], [180, 200], [180, 80]],
             [[400, 700], [400, 820], [520, 760]],
             [[80, 420], [80, 480], [170, 480], [170, 420]]]
    plan = meander(u_shape, holes, spacing=SPACING, turn_radius=6.0, swath=SWATH)
    assert coverage_fraction(plan, u_shape, holes, SWATH) >= 0.995
    path = LineString(plan.waypoints[:, ::-1])
    for hole in holes:
        assert shapely.distance(path, xy(hole)) >= 0.9                          # half the default clearance
    assert plan.length_m <= baseline_boustrophedon(u_shape, holes, SPACING, 6.0, swath=SWATH).length_m + 1e-6


def test_large_orderings_fall_back_to_the_heuristic_and_still_fly_every_task_once():
    rng = np.random.default_rng(3)
    n_tasks, per = 12, 8                                    # too many variants for the exact search
    pts = rng.uniform(0, 1000, size=(n_tasks * per, 2))
    cost = np.linalg.norm(pts[:, None] - pts[None], axis=2)
    task_of = np.repeat(np.arange(n_tasks), per)
    cost[task_of[:, None] == task_of[None, :]] = np.inf
    order = order_variants(task_of, np.arange(n_tasks * per) ^ 1, cost, np.zeros(len(pts)), np.zeros(len(pts)))
    assert sorted(task_of[order].tolist()) == list(range(n_tasks))
    nearest = [int(np.argmin(np.where(task_of == t, 0.0, np.inf))) for t in range(n_tasks)]
    assert tour_cost(order, cost, np.zeros(len(pts)), np.zeros(len(pts))) < tour_cost(
        nearest, cost, np.zeros(len(pts)), np.zeros(len(pts)))


def test_the_heuristic_ordering_finds_the_line_of_tasks_from_its_far_end():
    # 14 tasks on a line 100 m apart, each a single point flown either way: the exact search is too big, a
    # nearest-neighbour tour from task 0 (in the middle) zigzags; the best tour runs from one end to the other
    n_tasks = 14
    x = np.array([0, 7, 6, 8, 5, 9, 4, 10, 3, 11, 2, 12, 1, 13], dtype=float) * 100.0
    pts = np.repeat(np.stack([x, np.zeros(n_tasks)], axis=1), 2, axis=0)
    cost = np.linalg.norm(pts[:, None] - pts[None], axis=2)
    task_of = np.repeat(np.arange(n_tasks), 2)
    cost[task_of[:, None] == task_of[None, :]] = np.inf
    order = order_variants(task_of, np.arange(2 * n_tasks) ^ 1, cost, np.zeros(len(pts)), np.zeros(len(pts)))
    assert sorted(task_of[order].tolist()) == list(range(n_tasks))
    assert tour_cost(order, cost, np.zeros(len(pts)), np.zeros(len(pts))) == 1300.0


def test_the_heuristic_ordering_ends_when_transits_flown_backwards_cost_more():
    # a transit and its mirror (both tasks flown the other way) may differ by a loop of a Dubins turn (2πR); the
    # 2-opt moves, which count only the transits at the ends of the stretch they reverse, must not undo each other
    # for ever (these costs made them do so)
    rng = np.random.default_rng(72)
    n_tasks = 14
    pts = np.repeat(rng.uniform(0, 300, size=(n_tasks, 2)), 2, axis=0)
    cost = np.linalg.norm(pts[:, None] - pts[None], axis=2) + rng.choice([0.0, 37.7], size=(len(pts), len(pts)))
    task_of = np.repeat(np.arange(n_tasks), 2)
    cost[task_of[:, None] == task_of[None, :]] = np.inf
    order = order_variants(task_of, np.arange(len(pts)) ^ 1, cost, np.zeros(len(pts)), np.zeros(len(pts)))
    assert sorted(task_of[order].tolist()) == list(range(n_tasks))


def test_the_order_counts_how_long_each_way_of_flying_a_cell_is():
    # a cell flown one way is a straight 100 m line east; the other way (same ends and headings) it makes a 50 m
    # dog-leg north and back, 100 m longer: with the transits alike either way, the straight one is flown
    scene = Scene.build([[0, 0], [0, 400], [300, 400], [300, 0]], [], 6.0, 2.0, SWATH)
    east = np.array([[0.0, 0.0], [100.0, 0.0]])
    short = Run(east, (east,), 0.0, 0.0)
    long_ = Run(np.array([[0.0, 0.0], [50.0, 0.0], [50.0, 50.0], [50.0, 0.0], [100.0, 0.0]]), (east,), 0.0, 0.0)
    other = Run(np.array([[200.0, 0.0], [300.0, 0.0]]), (np.array([[200.0, 0.0], [300.0, 0.0]]),), 0.0, 0.0)
    runs = order_tasks(scene, [[long_, long_.reversed(), short, short.reversed()], [other, other.reversed()]])
    assert sum(run.length for run in runs) == 200.0


def test_a_start_point_shut_in_by_a_zone_still_gets_the_whole_survey():
    rect = [[0, 0], [0, 400], [300, 400], [300, 0]]
    hole = [[100, 150], [100, 250], [200, 250], [200, 150]]
    for start, finish in (([150, 200], None), ([150, 200], [150, 200])):       # no route leaves the zone
        plan = meander(rect, [hole], spacing=SPACING, turn_radius=6.0, swath=SWATH, start=start, finish=finish)
        assert len(plan.lines) >= 6
        assert coverage_fraction(plan, rect, [hole], SWATH) >= 0.995


def test_the_outermost_lines_stand_in_by_the_swath_overlap_and_save_a_line():
    # 310 m across at 50 m spacing needs ceil(310 / 50) = 7 lines at half a spacing from the edges; a 62.5 m swath
    # reaches 6.25 m beyond its band, so lines standing 0.9 of that further in cover it with ceil(298.75 / 50) = 6
    rect = [[0, 0], [0, 400], [310, 400], [310, 0]]
    plan = meander(rect, spacing=SPACING, heading=90.0, swath=SWATH)
    assert len(plan.lines) == 6
    assert coverage_fraction(plan, rect, [], SWATH) >= 0.999
    assert len(meander(rect, spacing=SPACING, heading=90.0, swath=SPACING).lines) == 7    # no overlap, no saving


def test_tiny_areas_order_more_drafts_in_full():
    def square(side):
        return Scene.build([[0, 0], [0, side], [side, side], [side, 0]], [], 6.0, 2.0, SWATH)

    assert [_full_plans(square(side)) for side in (300.0, 600.0, 1000.0)] == [6, 4, 2]   # 0.09, 0.36, 1 km²
