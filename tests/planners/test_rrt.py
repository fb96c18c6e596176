"""RRT planning in a voxel grid (seed 002 §2.2.1–2.2.2): safety against a hand-built grid, the Dubins radius, the
information-weighted objective, and the photo survey's coverage and densification."""

import math

import numpy as np
import pytest

pytest.importorskip("ompl")

from planners.rrt import ClearanceGrid, InformationField, photo_survey_path, plan_path  # noqa: E402
from planners.rrt.information import resample  # noqa: E402

CELL = 1.0


def wall_grid():
    """A 40 × 30 × 8 m grid (1 m voxels): a wall across north 18–21 with a gap at east 17–24, and a pillar."""
    occ = np.zeros((40, 30, 8), dtype=bool)
    occ[18:21, :17, :] = True
    occ[18:21, 24:, :] = True
    occ[8:10, 10:12, :] = True
    return occ


def distance_to_voxels(points, occ, cell=CELL):
    """Exact distance from each point to the nearest occupied voxel box (brute force)."""
    lo = np.argwhere(occ) * cell
    hi = lo + cell
    gap = np.maximum(np.maximum(lo[None] - points[:, None], points[:, None] - hi[None]), 0.0)
    return np.linalg.norm(gap, axis=2).min(axis=1)


def fine_samples(points, spacing=0.02):
    return resample(points, spacing)


@pytest.mark.parametrize("planner", ["RRTConnect", "RRTstar", "BITstar"])
def test_every_point_of_a_planned_path_keeps_the_safety_distance_from_occupied_voxels(planner):
    occ = wall_grid()
    grid = ClearanceGrid.from_occupancy(occ, (0, 0, 0), CELL)
    result = plan_path(grid, (4, 4, 4), (36, 4, 4), safety_distance=1.5, planner=planner, time_limit_s=0.3, seed=3)
    assert result.solved and result.planner == planner
    assert np.allclose(result.points[0], (4, 4, 4)) and np.allclose(result.points[-1], (36, 4, 4))
    d = distance_to_voxels(fine_samples(result.points), occ)
    assert d.min() >= 1.5
    assert result.length == pytest.approx(np.linalg.norm(np.diff(result.points, axis=0), axis=1).sum())


def test_a_start_inside_the_safety_margin_is_refused():
    grid = ClearanceGrid.from_occupancy(wall_grid(), (0, 0, 0), CELL)
    with pytest.raises(ValueError, match="clear of obstacles"):
        plan_path(grid, (17, 4, 4), (36, 4, 4), safety_distance=1.5)


def test_unknown_space_can_count_as_an_obstacle_or_be_forbidden():
    states = np.zeros((10, 10, 4), dtype=np.int8)
    states[5, 5, :] = 1
    states[0:2, :, :] = -1
    as_obstacle = ClearanceGrid.from_states(states, (0, 0, 0), 1.0, unknown="obstacle")
    forbidden = ClearanceGrid.from_states(states, (0, 0, 0), 1.0, unknown="forbid")
    free = ClearanceGrid.from_states(states, (0, 0, 0), 1.0, unknown="free")
    p = np.array([[3.5, 1.5, 1.5], [1.5, 8.5, 1.5]])
    assert as_obstacle.at(p).tolist() == [1.0, 0.0]
    assert forbidden.at(p) == pytest.approx([math.sqrt(10.0), 0.0])  # unknown voxels themselves are off limits
    assert free.at(p) == pytest.approx([math.sqrt(10.0), math.sqrt(13.0)])


def test_clearance_grid_from_a_voxel_map_reads_its_occupied_free_and_unknown_voxels():
    from planners.occupancy import VoxelMap

    vm = VoxelMap(1.0)
    vm.insert_scan([0.5, 2.5, 2.5], [[7.5, 2.5, 2.5]])  # free along north 0–7, occupied at 7
    grid = ClearanceGrid.from_voxel_map(vm, (0, 0, 0), (10, 5, 5), unknown="forbid")
    assert grid.shape == (10, 5, 5)
    along = grid.distance[:, 2, 2]
    assert along[7] == 0.0 and along[5] == 1.0 and along[3] == 3.0  # box distances to the occupied voxel
    assert grid.distance[3, 0, 0] == 0.0  # never observed: forbidden


def test_dubins_path_respects_the_turning_radius_and_the_safety_distance():
    occ = wall_grid()
    grid = ClearanceGrid.from_occupancy(occ, (0, 0, 0), CELL)
    radius = 4.0
    result = plan_path(grid, (4, 8, 3, 90.0), (34, 8, 5, 270.0), safety_distance=1.5, planner="RRTstar",
                       time_limit_s=0.5, turning_radius=radius, seed=1)
    assert result.solved and len(result.headings_deg) == len(result.points)
    assert result.headings_deg[0] == pytest.approx(90.0) and result.headings_deg[-1] == pytest.approx(270.0)
    # Horizontally the path is arcs of the turning radius and straights: three consecutive samples never lie on a
    # circle tighter than the radius.
    xy = result.points[:, :2]
    a, b, c = xy[:-2], xy[1:-1], xy[2:]
    ab, bc, ca = (np.linalg.norm(b - a, axis=1), np.linalg.norm(c - b, axis=1), np.linalg.norm(a - c, axis=1))
    cross = np.abs((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])
    ok = (ab > 1e-6) & (bc > 1e-6) & (cross > 1e-9)
    circumradius = ab[ok] * bc[ok] * ca[ok] / (2.0 * cross[ok])
    assert circumradius.min() >= radius * 0.99
    assert distance_to_voxels(fine_samples(result.points), occ).min() >= 1.5


def test_information_weighted_objective_flies_more_path_over_an_informative_strip():
    occ = np.zeros((50, 40, 6), dtype=bool)
    grid = ClearanceGrid.from_occupancy(occ, (0, 0, 0), CELL)
    info = np.zeros((50, 40))
    info[8:43, 24:30] = 1.0  # a strip 10–15 m east of the straight line between start and goal
    field = InformationField(info, north0=0.0, east0=0.0, cell=1.0)

    def over_strip(points):
        p = fine_samples(points, 0.1)
        mid = 0.5 * (p[1:] + p[:-1])
        inside = (mid[:, 1] >= 23.5) & (mid[:, 1] < 29.5) & (mid[:, 0] >= 7.5) & (mid[:, 0] < 42.5)
        return float(np.linalg.norm(np.diff(p, axis=0), axis=1)[inside].sum())

    plain = plan_path(grid, (5, 14, 3), (45, 14, 3), safety_distance=0.5, planner="RRTstar", iterations=3000,
                      time_limit_s=0.0, seed=7)
    weighted = plan_path(grid, (5, 14, 3), (45, 14, 3), safety_distance=0.5, planner="RRTstar", iterations=3000,
                         time_limit_s=0.0, seed=7, information=field)
    assert plain.solved and weighted.solved
    assert over_strip(weighted.points) > over_strip(plain.points) + 15.0
    assert weighted.information == pytest.approx(over_strip(weighted.points), rel=0.1)
    assert weighted.length > plain.length  # the detour is longer, yet cheaper in the weighted cost


def test_photo_survey_covers_the_area_and_packs_passes_over_informative_ground():
    info = np.zeros((81, 41))
    info[:, 18:23] = 1.0  # an informative strip along north, east 18–22
    field = InformationField(info, 0.0, 0.0, 1.0)
    area = [[0, 0], [80, 0], [80, 40], [0, 40]]
    survey = photo_survey_path(area, field, altitude=4.0, depth=10.0, fov_deg=(60.0, 45.0), overlap=0.5, gain=2.0,
                               turning_radius=2.0)
    across = survey.footprint[0]
    assert survey.heading_deg == pytest.approx(0.0)  # passes along the long side: fewest turns
    east = np.array([p[0, 1] for p in survey.passes])
    gaps = np.diff(np.sort(east))
    assert gaps.max() <= survey.base_spacing + 1e-9  # never sparser than the overlap asks
    # Every point of the area lies inside some pass's footprint.
    nn, ee = np.meshgrid(np.linspace(0, 80, 81), np.linspace(0, 40, 81), indexing="ij")
    nearest = np.abs(ee.ravel()[:, None] - east[None]).min(axis=1)
    assert nearest.max() <= across / 2.0 + 1e-9
    assert all(p[:, 0].min() <= 0.0 + 1e-9 and p[:, 0].max() >= 80.0 - 1e-9 for p in survey.passes)
    # Denser over the strip: passes per metre across the strip ≥ 2× elsewhere.
    in_strip = ((east > 17.5) & (east < 22.5)).sum() / 5.0
    elsewhere = ((east < 12.0) | (east > 28.0)).sum() / (40.0 - 16.0)
    assert in_strip >= 2.0 * elsewhere
    # The flown path links the passes with turns and keeps the survey depth.
    assert np.allclose(survey.path[:, 2], 10.0)
    steps = np.linalg.norm(np.diff(survey.path, axis=0), axis=1)
    assert steps.max() <= 80.0 + 1e-9 and len(survey.photo_points) > len(survey.passes) * 10
    assert math.isclose(survey.length, steps.sum())
