"""Contour passes round no-go zones and the cut lines next to them (seed 002 §2.1), against hand geometry: a
400 m × 300 m rectangle with a 100 m square zone in its middle, lines running east 50 m apart."""

import math

import numpy as np
import shapely
from shapely.geometry import LineString, box

from planners.coverage import coverage_fraction, meander
from planners.coverage.contours import contour_rings, contour_runs
from planners.coverage.metrics import swept
from planners.coverage.scene import Scene
from planners.coverage.sweep import build_sweep
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
    for seg in east_west:                                                        # end at the standoff, R + clearance
        assert shapely.distance(LineString(seg[:, ::-1]), zone) >= 8.0 - 0.5


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
