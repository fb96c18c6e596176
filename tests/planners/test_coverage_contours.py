"""Contour passes round no-go zones and the cut lines next to them (seed 002 §2.1), against hand geometry: a
400 m × 300 m rectangle with a 100 m square zone in its middle, lines running east 50 m apart."""

import math

import numpy as np
import pytest
import shapely
from shapely.geometry import LineString, box
from turning import circumradii

from planners.coverage import coverage_fraction, meander
from planners.coverage.contours import contour_rings, contour_runs
from planners.coverage.metrics import swept
from planners.coverage.scene import Scene
from planners.coverage.sweep import Passing, build_sweep
from planners.coverage.trims import trim_to_need
from planners.coverage.turns import dubins_path

RECT = [[0, 0], [0, 400], [300, 400], [300, 0]]             # 300 m north × 400 m east
HOLE = [[100, 150], [100, 250], [200, 250], [200, 150]]      # x (east) 150…250, y (north) 100…200
SPACING = 50.0
SWATH = SPACING / 0.8                                        # 20 % overlap: a line covers 31.25 m either side


def residual_of_lines(scene, heading):
    sweep = build_sweep(scene.region, scene.forbidden, heading, SPACING)
    lines = [sweep.points(np.array([p.u0, p.u1]), np.array([p.v, p.v])) for p in sweep.pieces]
    return scene.free.difference(swept(lines, SWATH))


def test_contour_passes_fly_only_the_zone_sides_the_lines_leave_uncovered():
    scene = Scene.build(RECT, [HOLE], 6.0, 2.0, SWATH)
    # rows at y = 25, 75 … 275: those at 75 and 225 pass 25 m from the zone and cover its north and south margins;
    # those at 125 and 175 stop 8 m (the standoff) short of its west and east sides, which only passes there cover
    residual = residual_of_lines(scene, 90.0)
    runs = contour_runs(scene, residual, SPACING, 1e-3)
    ring = contour_rings(scene, SPACING)[0]
    perimeter = float(np.linalg.norm(np.diff(ring, axis=0), axis=1).sum())
    flown = sum(run.length for run in runs)
    assert len(runs) == 2                                          # the west side and the east side
    assert 2 * 90.0 <= flown < 0.6 * perimeter                    # about the two 100 m sides; the ring is 450 m
    for run in runs:                                               # each runs along one side, north-south
        xs = run.path[:, 0]
        assert xs.max() - xs.min() < 2.0 * scene.standoff + 1e-6
    left = residual.difference(swept([seg for run in runs for seg in run.lines], SWATH))
    assert left.area <= 1e-3 * scene.free.area


def test_the_rectangle_with_a_square_zone_is_covered_and_the_path_keeps_out_of_the_zone():
    plan = meander(RECT, [HOLE], spacing=SPACING, heading=90.0, turn_radius=6.0, swath=SWATH)
    assert coverage_fraction(plan, RECT, [HOLE], SWATH) >= 0.999
    zone = shapely.Polygon([(e, n) for n, e in HOLE])
    assert shapely.distance(LineString(plan.waypoints[:, ::-1]), zone) >= 0.9    # half the 2 m clearance, rounded
    east_west = [seg for seg in plan.lines if abs(seg[0, 0] - seg[1, 0]) < 1e-6]
    assert len(east_west) >= 6                                                   # the survey lines
    for seg in east_west:
        gap = shapely.distance(LineString(seg[:, ::-1]), zone)
        if 100.0 < seg[0, 0] < 200.0:                                            # cut at the zone: they end at the
            assert gap >= 8.0 - 0.5                                              # standoff, R + clearance
        else:                                                                    # run or bend past it (a slid grid
            assert gap >= 2.0                                                    # may pass it): the clearance


def test_a_finer_sliver_keeps_the_small_parts_of_a_band_a_coarser_one_gives_up():
    sweep = build_sweep(box(0, 0, 400, 50), box(0, 0, 0, 0), 90.0, 50.0)        # one row of a line running east
    need = box(0, 0, 200, 50).union(box(390, 0, 391, 0.5))                      # 0.5 m² far east: 2e-4 spacing²
    coarse = trim_to_need(sweep, need)
    fine = trim_to_need(sweep, need, sliver=1e-5)
    assert [round(p.u1) for p in coarse.pieces] == [200]
    assert [round(p.u1) for p in fine.pieces] == [391]


def test_a_transit_between_coinciding_poses_is_a_flyable_two_point_path():
    pts = dubins_path([10.0, 5.0], 0.3, [10.0, 5.0], 0.3, 6.0)
    assert pts.shape == (2, 2) and np.allclose(pts, [[10.0, 5.0], [10.0, 5.0]])
    assert math.isclose(float(np.linalg.norm(np.diff(pts, axis=0), axis=1).sum()), 0.0)


def test_a_transit_round_a_zone_keeps_out_of_it_and_adds_little_to_the_route_between_its_corners():
    scene = Scene.build(RECT, [HOLE], 6.0, 2.0, SWATH)
    p, q = np.array([100.0, 150.0]), np.array([300.0, 150.0])          # either side of the zone, flying east
    path = scene.transit(p, 0.0, q, 0.0)
    assert np.allclose(path[0], p) and np.allclose(path[-1], q)
    zone = shapely.Polygon([(e, n) for n, e in HOLE])
    assert shapely.distance(LineString(path), zone) >= 0.9
    routed = float(scene.router.lengths(p, q)[0, 0])
    flown = float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum())
    assert routed <= flown <= routed + math.pi * 6.0


SMALL = [[112, 180], [112, 200], [128, 200], [128, 180]]      # 20 m east × 16 m north, across the row at y ≈ 123.6


def test_a_small_zone_across_a_line_is_bypassed_by_a_detour_and_needs_no_contour_pass():
    # four rows (the outer ones stand in by the overlap) at y ≈ 29.2, 76.4, 123.6, 170.8: the third crosses the
    # zone; 6.45 m north takes it 2.05 m clear of it (more than the 5.6 m a whole row may shift, less than the
    # half spacing a detour may reach), so the line bends round the zone instead of stopping 8 m short of it
    rect = [[0, 0], [0, 400], [200, 400], [200, 0]]
    plan = meander(rect, [SMALL], spacing=SPACING, heading=90.0, turn_radius=6.0, swath=SWATH)
    assert plan.cells == 1 and plan.turns == 3                   # one meander, no split, no transit
    assert coverage_fraction(plan, rect, [SMALL], SWATH) >= 0.999
    zone = shapely.Polygon([(e, n) for n, e in SMALL])
    path = LineString(plan.waypoints[:, ::-1])
    assert shapely.distance(path, zone) >= 2.0                    # the detour keeps the clearance
    beside = shapely.get_coordinates(path.intersection(box(180, 100, 200, 150)))     # alongside the zone
    assert len(beside) and np.allclose(beside[:, 1], 130.05)      # 2.05 m north of it, running east-west
    # every pass runs east-west or is a straight of the detour, slanting at most 10°: none follows the zone round
    for seg in plan.lines:
        assert abs(seg[1, 0] - seg[0, 0]) <= abs(seg[1, 1] - seg[0, 1]) * math.tan(math.radians(10.0)) + 1e-6
    assert circumradii(plan.waypoints).min() >= 0.95 * 6.0


def test_a_line_runs_on_past_a_zone_it_only_grazes_and_slides_clear_of_one_it_clips():
    area = box(0, 0, 400, 100)                                   # rows at y = 25 and 75, lines running east

    def rows(zone, shift):
        forbidden = zone.buffer(8.0)                             # the standoff, R + clearance
        passing = Passing(zone.buffer(2.0), shift=shift)         # the clearance
        sweep = build_sweep(area.difference(forbidden), forbidden, 90.0, 50.0, passing=passing)
        return [(p.row, round(p.v, 2), round(p.u0), round(p.u1)) for p in sweep.pieces]

    # 3 m past the zone's edge: within the standoff, so a cut line would stop 8 m short of it on either side
    assert rows(box(180, 78, 220, 95), 0.0) == [(0, 25.0, 0, 400), (1, 75.0, 0, 400)]
    # 1 m into the zone's clearance: cut without a shift, one line 2.05 m south of the zone with a 5 m one
    assert rows(box(180, 76, 220, 95), 0.0) == [(0, 25.0, 0, 400), (1, 75.0, 0, 172), (1, 75.0, 228, 400)]
    assert rows(box(180, 76, 220, 95), 5.0) == [(0, 25.0, 0, 400), (1, 73.95, 0, 400)]



def test_a_slid_line_grid_lets_a_zone_fall_between_two_lines():
    area = box(0, 0, 400, 110)                                   # 30 m spacing: four rows, lines running east
    zone = box(150, 62, 250, 72)

    def rows(phase):
        sweep = build_sweep(area.difference(zone), zone, 90.0, 30.0, phase=phase)
        return sweep, [(p.row, round(p.v, 2), round(p.u0), round(p.u1)) for p in sweep.pieces]

    # rounded to whole rows, 27.5 m apart: the row at y = 68.75 crosses the zone and splits
    sweep, pieces = rows(None)
    assert sweep.spacing == pytest.approx(27.5) and sweep.reach == (0.0, 0.0)
    assert [p[:2] for p in pieces] == [(0, 13.75), (1, 41.25), (2, 68.75), (2, 68.75), (3, 96.25)]
    # a full 30 m apart, the four rows span 120 m, 10 m beyond the area: slid to the south end of that slack the
    # zone (y 62…72) falls between the rows at y = 45 and 75 and splits none; the last band's share overhangs the
    # area by 10 m, and its line (at y = 105, inside the area) covers the band's 20 m within it
    sweep, pieces = rows(0.0)
    assert sweep.spacing == pytest.approx(30.0) and sweep.reach == pytest.approx((0.0, -10.0))
    assert pieces == [(0, 15.0, 0, 400), (1, 45.0, 0, 400), (2, 75.0, 0, 400), (3, 105.0, 0, 400)]
    # slid to the north end, the row at y = 65 splits
    sweep, pieces = rows(1.0)
    assert sweep.reach == pytest.approx((-10.0, 0.0))
    assert [p[:2] for p in pieces] == [(0, 5.0), (1, 35.0), (2, 65.0), (2, 65.0), (3, 95.0)]


def test_a_slid_line_grid_keeps_its_outermost_lines_within_the_area():
    # 100 m across at 30 m: a full-spacing grid would overhang by 20 m and put a line 5 m outside; the rows close
    # up instead (100 / 3.5 m apart), so that the outermost line runs along the area's edge
    sweep = build_sweep(box(0, 0, 400, 100), box(0, 0, 0, 0), 90.0, 30.0, phase=0.0)
    assert sweep.spacing == pytest.approx(100 / 3.5)
    assert [round(p.v, 2) for p in sweep.pieces] == [14.29, 42.86, 71.43, 100.0]


def test_contour_passes_bridge_short_gaps_unless_asked_not_to():
    scene = Scene.build(RECT, [HOLE], 6.0, 2.0, SWATH)
    # two patches beside the zone's west side (the ring runs north at x = 142), 52 m apart along it
    residual = box(136, 105, 141, 108).union(box(136, 160, 141, 163))
    bridged = contour_runs(scene, residual, SPACING, 0.0)                # gaps under a spacing flown through
    apart = contour_runs(scene, residual, SPACING, 0.0, bridge=0.0)      # each patch its own pass
    assert len(bridged) == 1 and len(apart) == 2
    assert sum(run.length for run in apart) < bridged[0].length - 10.0
    for runs in (bridged, apart):
        assert residual.difference(swept([seg for run in runs for seg in run.lines], SWATH)).area < 1e-6


def test_the_area_left_to_contour_passes_shrinks_exactly_as_a_whole_polygon_would():
    from planners.coverage.contours import _Parts

    rng = np.random.default_rng(3)
    blobs = [shapely.Point(x, y).buffer(r) for x, y, r in zip(rng.uniform(0, 500, 30), rng.uniform(0, 500, 30),
                                                             rng.uniform(5, 40, 30), strict=True)]
    whole = shapely.union_all(blobs)
    left = _Parts(whole)
    for x, y in rng.uniform(0, 500, (12, 2)):
        cover = LineString([(x, y), (x + 120.0, y + 40.0)]).buffer(30.0, cap_style="flat")
        assert left.area_in(cover) == pytest.approx(whole.intersection(cover).area, rel=1e-9, abs=1e-6)
        left.remove(cover)
        whole = whole.difference(cover)
        assert left.area == pytest.approx(whole.area, rel=1e-9)
