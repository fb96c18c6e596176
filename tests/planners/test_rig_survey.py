"""The informative photo survey (seed 002 §2.2.1): a RIG tree over the information map, flown as Dubins curves.

One hand-built world: a 40 × 40 m area on a 0.5 m clearance grid with a pillar through the survey depth, and an
information map with two informative patches (one round the pillar) on blank ground."""

import numpy as np
import pytest

pytest.importorskip("ompl")

from turning import circumradii  # noqa: E402

from planners.rrt import ClearanceGrid, InformationField, informative_survey_path, photo_survey_path  # noqa: E402
from planners.rrt.information import resample  # noqa: E402
from planners.rrt.photo import footprint  # noqa: E402
from planners.rrt.photo_gain import PhotoModel, path_headings, truncate  # noqa: E402

AREA = np.array([[0.0, 0.0], [0.0, 40.0], [40.0, 40.0], [40.0, 0.0]])
DEPTH, ALTITUDE, RADIUS, SAFETY, BUDGET = 25.0, 5.0, 3.0, 1.0, 160.0
VOXEL = 0.5
PILLAR = (slice(int(48 / VOXEL), int(50 / VOXEL)), slice(int(48 / VOXEL), int(50 / VOXEL)))  # north, east 28–30


def world():
    """Obstacles (20 m of margin around the area, 0.5 m voxels, depth 20–30 m) and the information field."""
    n = int(80 / VOXEL)
    occ = np.zeros((n, n, int(10 / VOXEL)), dtype=bool)
    occ[PILLAR] = True
    grid = ClearanceGrid.from_occupancy(occ, (-20.0, -20.0, 20.0), VOXEL)
    info = np.zeros((60, 60))  # 1 m cells, centres at −9.5 … 49.5
    info[37:41, 36:42] = 1.0  # a patch round the pillar (north 27–31, east 26–32)
    info[18:22, 14:20] = 0.8  # another at north 8–12, east 4–10
    return occ, grid, InformationField(info, north0=-9.5, east0=-9.5, cell=1.0)


def plan(budget=BUDGET, seed=3):
    _, grid, field = world()
    return informative_survey_path(AREA, field, budget=budget, altitude=ALTITUDE, depth=DEPTH,
                                   turning_radius=RADIUS, start=(0.0, 20.0), start_heading_deg=0.0, clearance=grid,
                                   safety_distance=SAFETY, seed=seed)


@pytest.fixture(scope="module")
def survey():
    return plan()


def distance_to_voxels(points, occ, origin, cell):
    lo = np.argwhere(occ) * cell + origin
    hi = lo + cell
    gap = np.maximum(np.maximum(lo[None] - points[:, None], points[:, None] - hi[None]), 0.0)
    return np.linalg.norm(gap, axis=2).min(axis=1)


def info_per_metre(field, path, photos, budget):
    model = PhotoModel(field, *footprint(ALTITUDE, (60.0, 45.0)))
    p, q = truncate(path, photos, budget)
    length = float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())
    return model.revealed(model.counts(q, path_headings(p, q))) / length


def test_a_short_budget_is_flown_to_its_end_and_never_exceeded():
    short = plan(budget=50.0)
    assert 45.0 <= short.length <= 50.0 + 1e-6


def test_it_stops_short_of_a_long_budget_once_the_information_is_photographed():
    _, _, field = world()
    long = plan(budget=1000.0)
    model = PhotoModel(field, *long.footprint)
    counts = model.counts(long.photo_points, np.radians(long.photo_headings_deg))
    assert model.high_share(counts) >= 0.95 and long.length < 400.0


def test_no_point_of_the_path_comes_within_the_safety_distance_of_the_pillar(survey):
    occ, grid, _ = world()
    fine = resample(survey.path, 0.05)
    near = fine[np.hypot(fine[:, 0] - 29.0, fine[:, 1] - 29.0) < 8.0]  # only the pillar is near the survey depth
    closest = distance_to_voxels(near, occ, grid.origin, VOXEL).min()
    assert SAFETY <= closest < SAFETY + 1.5  # the patch round the pillar draws the path close to it


def test_the_path_keeps_the_turning_radius(survey):
    xy = survey.path[:, :2]
    steps = np.linalg.norm(np.diff(xy, axis=0), axis=1)
    assert steps.max() <= 0.5 + 1e-6
    radii = circumradii(xy[np.r_[True, steps > 1e-6]])
    assert radii.min() >= RADIUS * 0.98


def test_it_photographs_more_information_per_metre_than_the_lawnmower_at_the_same_budget(survey):
    _, grid, field = world()
    lawn = photo_survey_path(AREA, field, altitude=ALTITUDE, depth=DEPTH, fov_deg=(60.0, 45.0), overlap=0.6,
                             gain=2.0, turning_radius=RADIUS)
    ours = info_per_metre(field, survey.path, survey.photo_points, BUDGET)
    theirs = info_per_metre(field, lawn.path, lawn.photo_points, BUDGET)
    assert ours >= 2.0 * theirs


def test_informative_ground_is_photographed_more_often_than_blank_ground(survey):
    _, _, field = world()
    model = PhotoModel(field, *survey.footprint)
    counts = model.counts(survey.photo_points, np.radians(survey.photo_headings_deg)).reshape(model.shape)
    patches = np.concatenate([counts[37:41, 36:42].ravel(), counts[18:22, 14:20].ravel()])
    assert np.mean(patches >= 2) >= 0.8  # the cells next to the pillar are harder to reach
    blank = counts[10:50, 10:50][field.normalised()[10:50, 10:50] < 0.05]
    assert patches.mean() > 3.0 * blank.mean()


def test_a_plan_repeats_exactly_for_its_seed(survey):
    again = plan()
    np.testing.assert_array_equal(again.path, survey.path)
    np.testing.assert_array_equal(again.photo_points, survey.photo_points)


def test_a_start_inside_the_safety_margin_is_refused():
    _, grid, field = world()
    with pytest.raises(ValueError, match="within"):
        informative_survey_path(AREA, field, budget=50.0, altitude=ALTITUDE, depth=DEPTH, turning_radius=RADIUS,
                                start=(29.0, 29.0), start_heading_deg=0.0, clearance=grid, safety_distance=SAFETY)
