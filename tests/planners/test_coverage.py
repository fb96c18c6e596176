"""Coverage planning (seed 002 §2.1): spacing from swath and overlap, meanders over polygons with no-go zones,
turns within the turning radius, start and finish, against hand geometry."""

import math

import numpy as np
import pytest
import shapely
from shapely.geometry import LineString, Polygon
from turning import circumradii

from planners.coverage import (
    CoveragePlan,
    baseline_boustrophedon,
    coverage_fraction,
    line_spacing,
    line_spacing_over_terrain,
    meander,
    swath_width,
)

RECT = [[0, 0], [0, 400], [300, 400], [300, 0]]            # 300 m north × 400 m east
HOLE = [[100, 150], [100, 250], [200, 250], [200, 150]]     # a no-go zone in its middle
SPACING = 50.0
SWATH = SPACING / 0.8                                       # 20 % overlap


def zone_xy(zone):
    return Polygon([(e, n) for n, e in zone])


def test_swath_and_spacing_match_hand_numbers():
    assert swath_width(20.0, 120.0) == pytest.approx(2 * 20 * math.sqrt(3))          # 69.28 m
    assert line_spacing(20.0, 120.0, 20.0) == pytest.approx(0.8 * 40 * math.sqrt(3))  # 55.43 m
    assert line_spacing(20.0, 90.0, 50.0) == pytest.approx(20.0)


def test_spacing_is_taken_over_the_highest_ground():
    # 5 m of relief leaves 15 m of altitude there: the swath, and with it the spacing, shrinks by a quarter
    assert line_spacing(20.0, 120.0, 20.0, relief=5.0) == pytest.approx(0.75 * line_spacing(20.0, 120.0, 20.0))
    depths = np.full(1000, 100.0)
    depths[:100] = 94.0                                    # a tenth of the area rises 6 m; mean depth 99.4 m
    assert line_spacing_over_terrain(20.0, 120.0, 20.0, depths) == pytest.approx(
        line_spacing(20.0, 120.0, 20.0, relief=5.4))
    with pytest.raises(ValueError):
        line_spacing(20.0, 120.0, 20.0, relief=25.0)


def test_rectangle_gets_one_line_per_spacing_and_is_covered():
    plan = meander(RECT, spacing=SPACING, heading=90.0, swath=SWATH)
    assert len(plan.lines) == 6 and plan.turns == 5 and plan.cells == 1
    norths = np.array(sorted(float(line[0, 0]) for line in plan.lines))
    # evenly spread, at most a spacing apart; the outermost stand in from the boundary by less than half a swath
    # (the swath's overlap lets them stand further in than half a spacing)
    assert np.diff(norths) == pytest.approx(np.full(5, np.diff(norths).mean())) and np.diff(norths).max() <= SPACING
    assert norths[0] == pytest.approx(300 - norths[-1]) and SPACING / 2 <= norths[0] < SWATH / 2
    assert all(abs(line[1, 1] - line[0, 1]) == pytest.approx(400.0) for line in plan.lines)
    assert coverage_fraction(plan, RECT, [], SWATH) >= 0.995


def test_auto_heading_runs_lines_along_the_long_side_of_a_thin_rectangle():
    along = np.array([math.cos(math.radians(30)), math.sin(math.radians(30))])   # [north, east] at heading 30°
    across = np.array([-along[1], along[0]])
    thin = [list(p) for p in (0 * along, 1000 * along, 1000 * along + 120 * across, 120 * across)]
    plan = meander(thin, spacing=SPACING)
    assert min(abs(plan.heading_deg - 30.0), 180 - abs(plan.heading_deg - 30.0)) < 1.0
    assert len(plan.lines) == 3


def test_meander_covers_the_area_around_a_hole_without_entering_it():
    plan = meander(RECT, [HOLE], spacing=SPACING, turn_radius=6.0, swath=SWATH)
    assert coverage_fraction(plan, RECT, [HOLE], SWATH) >= 0.995
    inside = zone_xy(HOLE).buffer(-0.1)
    path = plan.waypoints[:, ::-1]
    segments = shapely.linestrings(np.stack([path[:-1], path[1:]], axis=1))
    assert not shapely.intersects(segments, inside).any()
    assert shapely.distance(LineString(path), zone_xy(HOLE)) >= 0.9      # half the default 2 m clearance


def test_a_zone_that_splits_the_lines_gives_several_cells_and_a_shorter_path():
    wide = [[0, 0], [0, 1200], [600, 1200], [600, 0]]
    zone = [[150, 400], [150, 800], [450, 800], [450, 400]]
    plan = meander(wide, [zone], spacing=SPACING, heading=90.0, turn_radius=6.0, swath=SWATH)
    assert plan.method == "boustrophedon-cells" and plan.cells >= 4
    base = baseline_boustrophedon(wide, [zone], SPACING, 6.0, swath=SWATH)
    assert plan.length_m < base.length_m
    assert coverage_fraction(plan, wide, [zone], SWATH) >= 0.995


def test_auto_plan_is_never_longer_than_the_single_direction_baseline():
    l_shape = [[0, 0], [0, 500], [200, 500], [200, 200], [450, 200], [450, 0]]
    zone = [[60, 300], [60, 360], [140, 360], [140, 300]]
    plan = meander(l_shape, [zone], spacing=SPACING, turn_radius=6.0, swath=SWATH)
    base = baseline_boustrophedon(l_shape, [zone], SPACING, 6.0, swath=SWATH)
    assert plan.length_m <= base.length_m + 1e-6
    assert coverage_fraction(plan, l_shape, [zone], SWATH) >= 0.995


def test_turns_between_lines_closer_than_twice_the_radius_keep_to_the_radius():
    radius = 15.0
    plan = meander([[0, 0], [0, 200], [60, 200], [60, 0]], spacing=10.0, heading=90.0, turn_radius=radius)
    assert plan.turns == 5
    assert circumradii(plan.waypoints).min() >= 0.95 * radius
    # Ω-turns bulge beyond the line ends but come back onto the next line
    assert plan.waypoints[:, 1].max() > 200 + radius


def test_u_turns_between_lines_wider_than_twice_the_radius_keep_to_the_radius():
    plan = meander(RECT, [HOLE], spacing=SPACING, turn_radius=6.0, swath=SWATH)
    assert circumradii(plan.waypoints).min() >= 0.95 * 6.0


def test_path_starts_and_finishes_near_the_given_points():
    plan = meander(RECT, spacing=SPACING, heading=90.0, start=[-20, 410], finish=[320, 420])
    assert np.linalg.norm(plan.waypoints[0] - [25, 400]) < 1e-6            # the corner line end nearest the start
    assert np.linalg.norm(plan.waypoints[-1] - [275, 400]) < 1e-6          # six lines: finish on the same side
    other = meander(RECT, spacing=SPACING, heading=90.0, start=[310, -5])
    assert np.linalg.norm(other.waypoints[0] - [275, 0]) < 1e-6


def test_coverage_fraction_counts_the_free_area_within_half_a_swath_of_the_passes():
    square = [[0, 0], [0, 100], [100, 100], [100, 0]]
    line = np.array([[50.0, 0.0], [50.0, 100.0]])                        # along east through the middle
    plan = CoveragePlan(line, [line], 90.0, 50.0, 0, 100.0, 1, "hand")
    assert coverage_fraction(plan, square, [], 50.0) == pytest.approx(0.5)
    top = [[60, 0], [60, 100], [100, 100], [100, 0]]                     # zone over the northern 40 m
    assert coverage_fraction(plan, square, [top], 50.0) == pytest.approx(35 / 60)


def test_bad_polygons_and_spacings_are_refused():
    with pytest.raises(ValueError, match="not a simple polygon"):
        meander([[0, 0], [100, 100], [0, 100], [100, 0]], spacing=SPACING)
    with pytest.raises(ValueError, match="spacing"):
        meander(RECT, spacing=0.0)
    with pytest.raises(ValueError, match="cover the whole"):
        meander(RECT, [[[-10, -10], [-10, 410], [310, 410], [310, -10]]], spacing=SPACING)


def test_transit_segments_are_clear_exactly_where_they_miss_every_zone():
    from planners.coverage.routes import Router

    zones = shapely.union_all([shapely.box(0, 0, 10, 10), shapely.box(30, 0, 40, 10),
                               Polygon([(15, 20), (25, 20), (20, 30)])])
    rng = np.random.default_rng(3)
    a, b = rng.uniform(-10, 50, (400, 2)), rng.uniform(-10, 50, (400, 2))
    router = Router(zones, zones)
    truth = ~shapely.intersects(shapely.linestrings(np.stack([a, b], axis=1)), zones)
    assert 50 < truth.sum() < 350                          # both kinds occur
    assert np.array_equal(router.clear(a, b), truth)
    assert router.clear([-5.0, 15.0], [45.0, 15.0]).tolist() == [True]        # between the squares and the triangle
    assert router.clear([-5.0, 5.0], [45.0, 5.0]).tolist() == [False]         # through both squares
