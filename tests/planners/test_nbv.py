"""Next-best-view scanning (seed 002 §2.2.2): the utility's terms on hand-built voxel scenes, frontier vs contour
weights, safe candidates, and the exploration loop against a synthetic scene's true geometry."""

import math

import numpy as np
import pytest

from planners.nbv import (
    CONTOUR,
    FRONTIER,
    Box,
    DerivedMaps,
    NbvPlanner,
    RecedingHorizonNbv,
    Scanner,
    Scene,
    StateGrid,
    View,
    Views,
    Weights,
    candidate_views,
    contour_mask,
    run_exploration,
    survey_scans,
    view_utility,
    visibility,
)
from planners.occupancy import VoxelMap

FREE, OCC, UNK = 0, 1, -1
DENSE = Scanner(fov_deg=(60.0, 45.0), max_range=8.0, rays=(121, 91))
RES = 0.25


def hand_built(shape):
    """A 1 m voxel grid with its corner at the origin, all known free."""
    return StateGrid(np.zeros(shape, dtype=np.int8), np.zeros(3, dtype=np.int64), 1.0)


def box_distance(points, keys):
    """Exact distance from points to the nearest of the unit voxel boxes with the given keys."""
    lo = np.asarray(keys, dtype=float)
    gap = np.maximum(np.maximum(lo[None] - points[:, None], points[:, None] - (lo[None] + 1.0)), 0.0)
    return np.linalg.norm(gap, axis=2).min(axis=1)


def block_and_plate():
    """A 3×3×3 block of unknown voxels 4.5 m ahead of the view, and a 3×3 plate of occupied voxels behind it."""
    grid = hand_built((12, 12, 12))
    grid.states[5:8, 5:8, 5:8] = UNK
    grid.states[8, 5:8, 5:8] = OCC
    grid.occupied_ids = np.flatnonzero(grid.states.reshape(-1) == OCC)
    return grid


def test_utility_terms_count_the_unknown_voxels_in_reach_and_the_structure_the_rays_stop_on():
    grid = block_and_plate()
    views = Views(np.array([[0.5, 6.5, 6.5], [0.5, 6.5, 6.5]]), np.array([0.0, 180.0]), np.zeros(2))
    terms = view_utility(grid, views, current=(0.5, 6.5, 6.5), scanner=DENSE, weights=Weights(0.3, 0.5, 0.2),
                         min_overlap=0.1, step=0.05)
    # Facing the block: all 27 unknown voxels lie in the frustum and within range; every plate voxel is hit and
    # is on the contour (its neighbours in the block are unknown voxels touching free space).
    assert terms.f.tolist() == [27, 0]
    assert terms.ct.tolist() == [9, 0]
    assert terms.occupied.tolist() == [9, 0]
    assert 0.0 < terms.hit_fraction[0] < 0.5 and terms.hit_fraction[1] == 0.0
    assert terms.ol.tolist() == [min(1.0, terms.hit_fraction[0] / 0.1), 0.0]
    assert terms.d.tolist() == [1.0, 1.0]  # both at the vehicle
    assert terms.u[0] == pytest.approx((terms.d[0] * 0.3 + 1.0 * 0.5 + 1.0 * 0.2) * terms.ol[0])
    assert terms.u[1] == 0.0


def test_distance_term_is_one_at_the_vehicle_and_decays_over_one_scanner_range():
    grid = hand_built((12, 12, 12))
    views = Views(np.array([[1.5, 1.5, 1.5], [4.5, 1.5, 1.5], [9.5, 1.5, 1.5]]), np.zeros(3), np.zeros(3))
    terms = view_utility(grid, views, current=(1.5, 1.5, 1.5), scanner=DENSE, weights=Weights())
    assert terms.d.tolist() == pytest.approx([1.0, math.exp(-3.0 / 8.0), math.exp(-1.0)])
    assert np.all((terms.d > 0.0) & (terms.d <= 1.0))


def test_unknown_space_behind_known_structure_is_not_counted():
    grid = block_and_plate()
    view = Views(np.array([[0.5, 6.5, 6.5]]), np.zeros(1), np.zeros(1))
    narrow = Scanner((20.0, 15.0), 12.0, (41, 31))  # every ray of it ends on the plate
    wide = Scanner((60.0, 45.0), 12.0, (61, 45))
    before_narrow = visibility(grid, view, narrow, step=0.05)
    before_wide = visibility(grid, view, wide, step=0.05)
    grid.states[9:11, 4:9, 4:9] = UNK  # a slab hidden behind the plate, larger than it
    after_narrow = visibility(grid, view, narrow, step=0.05)
    after_wide = visibility(grid, view, wide, step=0.05)
    assert before_narrow.hit_fraction[0] == 1.0
    assert after_narrow.unknown[0] == before_narrow.unknown[0]
    assert after_wide.unknown[0] > before_wide.unknown[0]  # seen past the plate's edges


def scene_for_behaviours():
    """A view facing a large unknown region (with a post in sight for overlap) and a view along a known wall whose
    continuation is unknown: the two behaviours of the seed's weights."""
    grid = hand_built((24, 24, 10))
    grid.states[14:22, 14:22, 1:9] = UNK  # unexplored space ahead of view F
    grid.states[12, 16, 1:9] = OCC  # a post F sees (overlap with known structure)
    grid.states[2:13, 3, 2:8] = OCC  # a wall C looks at…
    grid.states[2:13, 2, 2:8] = UNK  # …with unknown behind it (free beyond): every wall voxel is on the contour
    grid.occupied_ids = np.flatnonzero(grid.states.reshape(-1) == OCC)
    views = Views(np.array([[9.5, 17.5, 5.0], [7.5, 8.5, 5.0]]), np.array([0.0, 270.0]), np.zeros(2))
    return grid, views


def test_frontier_weights_pick_the_view_facing_unknown_space_and_contour_weights_the_view_along_structure():
    grid, views = scene_for_behaviours()
    scanner = Scanner((60.0, 45.0), 10.0, (48, 36))
    frontier = view_utility(grid, views, current=(8.5, 12.5, 5.0), scanner=scanner, weights=FRONTIER)
    contour = view_utility(grid, views, current=(8.5, 12.5, 5.0), scanner=scanner, weights=CONTOUR)
    assert frontier.f[0] > 10 * max(frontier.f[1], 1) and frontier.ct[1] > 10 * max(frontier.ct[0], 1)
    assert frontier.ol.tolist() == [1.0, 1.0]
    assert int(np.argmax(frontier.u)) == 0
    assert int(np.argmax(contour.u)) == 1


def test_weights_must_sum_to_one():
    with pytest.raises(ValueError, match="sum to 1"):
        Weights(0.5, 0.5, 0.5)


def test_contour_is_updated_region_by_region_as_the_full_recomputation_would():
    rng = np.random.default_rng(0)
    grid = hand_built((20, 18, 16))
    grid.states[...] = rng.choice(np.array([FREE, OCC, UNK], dtype=np.int8), size=grid.shape, p=[0.6, 0.2, 0.2])
    derived = DerivedMaps(grid, safety_cell=2.0)
    grid.states[5:9, 3:7, 8:12] = rng.choice(np.array([FREE, OCC, UNK], dtype=np.int8), size=(4, 4, 4))
    derived.update(np.array([5, 3, 8]), np.array([9, 7, 12]))
    assert np.array_equal(derived.contour, contour_mask(grid.states))
    fresh = DerivedMaps(grid, safety_cell=2.0)
    assert np.array_equal(derived.obstacle, fresh.obstacle)


def test_candidates_lie_in_known_free_space_at_the_safe_distance_from_structure():
    grid = hand_built((40, 40, 20))
    grid.states[17:23, 17:23, 8:20] = OCC  # a column standing on…
    grid.states[:, :, 19] = OCC  # …the seabed
    grid.states[0:3, :, :] = UNK  # and an unexplored slab
    grid.occupied_ids = np.flatnonzero(grid.states.reshape(-1) == OCC)
    derived = DerivedMaps(grid, safety_cell=1.0)
    views = candidate_views(grid, derived.safety, (8.0, 8.0, 8.0), Scanner((60.0, 45.0), 10.0), count=40,
                            safe_distance=3.0, rng=np.random.default_rng(1), contour=derived.contour_ids())
    assert len(views) == 40
    assert (grid.state(views.positions) == FREE).all()
    occupied = np.argwhere(grid.states == OCC)
    unknown = np.argwhere(grid.states == UNK)
    assert box_distance(views.positions, occupied).min() >= 3.0
    assert box_distance(views.positions, unknown).min() >= 3.0
    assert np.all(np.abs(views.pitch_deg) <= 30.0)


@pytest.fixture(scope="module")
def small_world():
    scene = Scene(boxes=(Box((10.1, 10.1, 16.0), (14.1, 14.1, 20.0)),), seabed_depth=20.0)
    lo, hi = np.array([2.0, 2.0, 8.0]), np.array([22.0, 22.0, 20.5])
    prior = survey_scans(scene, (2, 2), (22, 22), 8.0, 3.0, fov_deg=(90.0, 30.0), rays=(160, 60))
    truth = scene.surface_keys(RES)
    return scene, lo, hi, prior, truth


def fresh_map(prior, resolution=RES):
    vm = VoxelMap(resolution)
    for s in prior:
        vm.insert_scan(s.origin, s.endpoints, s.hit, max_range=60.0)
    return vm


def test_exploration_scans_the_object_and_never_comes_within_the_safe_distance_of_it(small_world):
    scene, lo, hi, prior, truth = small_world
    vm = fresh_map(prior)
    scanner = Scanner((60.0, 45.0), 8.0, (16, 12))
    planner = NbvPlanner(vm, lo, hi, scanner, weights=Weights(), safe_distance=2.0, candidates=60, seed=0)
    start = View.at((5.0, 12.0, 15.0), 0.0)

    def coverage():
        return float((vm.state(vm.centres(truth)) == 1).mean())

    before = coverage()
    log = run_exploration(planner, lambda v: scene.scan(v, scanner.with_rays((40, 30))), start, safe_distance=2.0,
                          coverage=coverage, coverage_target=0.9, max_views=25, seed=0)
    after = coverage()
    assert after >= 0.9 > before
    path = log.path
    dense = np.concatenate([a + np.linspace(0, 1, 40)[:, None] * (b - a)
                            for a, b in zip(path[:-1], path[1:], strict=True)])
    assert scene.distance(dense).min() >= 2.0
    lengths, cover = log.coverage_curve()
    assert np.all(np.diff(lengths) >= 0) and cover[-1] == pytest.approx(after)


def test_receding_horizon_baseline_executes_only_the_first_edge_of_its_best_branch(small_world):
    scene, lo, hi, prior, _ = small_world
    vm = fresh_map(prior)
    scanner = Scanner((60.0, 45.0), 8.0, (16, 12))
    base = RecedingHorizonNbv(vm, lo, hi, scanner, safe_distance=2.0, extension=2.0, seed=0)
    start = View.at((5.0, 12.0, 15.0), 0.0)
    base.integrate(scene.scan(start, scanner))
    first = base.propose(start)
    assert first is not None and base.last_nodes >= base.min_nodes
    assert np.linalg.norm(first.point - start.point) <= 2.0 + 1e-9
    remaining = [first.point] + [v.point for v in base.branch]
    assert all(np.linalg.norm(b - a) <= 2.0 + 1e-9 for a, b in zip(remaining[:-1], remaining[1:], strict=True))
    assert math.isclose(base.lam, 0.5)
