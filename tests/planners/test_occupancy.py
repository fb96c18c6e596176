"""The voxel occupancy map of seed 002 §2.1 against ground truth: log-odds arithmetic, free-space carving, exact
traversal (against a step-by-step Amanatides–Woo walk), the height map of a known seabed, and memory."""

import math

import numpy as np
import pytest

from planners.occupancy import LogOddsParams, VoxelMap, logit, ray_voxels

P = LogOddsParams()
TOL = P.quantum / 2  # voxels store log-odds as 16-bit codes; one update is exact to half a quantum


def reference_ray(origin, end, resolution):
    """Voxels from the origin voxel up to (not including) the end voxel, one Amanatides–Woo step at a time."""
    o, e = np.asarray(origin, float) / resolution, np.asarray(end, float) / resolution
    key, last = np.floor(o).astype(int), np.floor(e).astype(int)
    d = e - o
    step = np.sign(d).astype(int)
    with np.errstate(divide="ignore", invalid="ignore"):
        t_max = np.where(step != 0, (key + (step > 0) - o) / d, np.inf)
        t_delta = np.where(step != 0, 1.0 / np.abs(d), np.inf)
    voxels = []
    for _ in range(int(np.abs(last - key).sum())):
        voxels.append(tuple(key))
        axis = int(np.argmin(t_max))
        key[axis] += step[axis]
        t_max[axis] += t_delta[axis]
    assert tuple(key) == tuple(last)
    return voxels


def fan(origin, depth, beams=256, swath_deg=120.0, heading=0.0):
    """Endpoints of a sonar fan across track from `origin` down to a flat seabed at `depth` (z down)."""
    angles = np.radians(np.linspace(-swath_deg / 2, swath_deg / 2, beams))
    r = (depth - origin[2]) / np.cos(angles)
    across = np.array([-math.sin(math.radians(heading)), math.cos(math.radians(heading))])
    ends = np.empty((beams, 3))
    ends[:, 0] = origin[0] + across[0] * r * np.sin(angles)
    ends[:, 1] = origin[1] + across[1] * r * np.sin(angles)
    ends[:, 2] = depth
    return ends


def test_log_odds_params_default_to_octomap_and_validate():
    assert (P.p_hit, P.p_miss, P.clamp_min, P.clamp_max, P.occupied) == (0.7, 0.4, 0.12, 0.97, 0.5)
    assert P.hit == pytest.approx(math.log(0.7 / 0.3)) and P.miss == pytest.approx(math.log(0.4 / 0.6))
    assert P.quantum <= 2**-13
    with pytest.raises(ValueError, match="p_miss < 0.5 < p_hit"):
        LogOddsParams(p_hit=0.4)
    with pytest.raises(ValueError, match="strictly between 0 and 1"):
        LogOddsParams(clamp_max=1.0)


def test_unknown_voxels_have_zero_log_odds_and_state_minus_one():
    m = VoxelMap(0.5)
    pts = [[1.0, 2.0, 3.0], [-100.0, 5.0, 0.0]]
    assert m.log_odds(pts).tolist() == [0.0, 0.0]
    assert m.probability(pts).tolist() == [0.5, 0.5]
    assert m.state(pts).tolist() == [-1, -1]
    assert m.known_voxels == 0 and len(m.occupied_centres()) == 0


def test_one_hit_raises_a_voxels_log_odds_by_logit_p_hit():
    m = VoxelMap(0.5)
    m.insert_scan([0.1, 0.1, 0.1], [[0.1, 0.1, 4.1]])
    assert m.log_odds([[0.1, 0.1, 4.1]])[0] == pytest.approx(logit(0.7), abs=TOL)
    assert m.state([[0.1, 0.1, 4.1]])[0] == 1


def test_one_miss_lowers_a_voxels_log_odds_by_logit_p_miss():
    m = VoxelMap(0.5)
    m.insert_scan([0.1, 0.1, 0.1], [[0.1, 0.1, 4.1]])
    assert m.log_odds([[0.1, 0.1, 2.1]])[0] == pytest.approx(logit(0.4), abs=TOL)
    assert m.state([[0.1, 0.1, 2.1]])[0] == 0


def test_repeated_hits_clamp_at_logit_clamp_max():
    m = VoxelMap(0.5)
    values = []
    for _ in range(8):
        m.insert_scan([0.1, 0.1, 0.1], [[0.1, 0.1, 4.1]])
        values.append(m.log_odds([[0.1, 0.1, 4.1]])[0])
    assert values[1] == pytest.approx(2 * logit(0.7), abs=2 * TOL)
    assert values[-1] == pytest.approx(logit(0.97), abs=TOL) and max(values) <= logit(0.97) + TOL
    assert values.index(values[-1]) == 4  # 5 hits (5 · 0.847 > 3.476) reach the clamp


def test_repeated_misses_clamp_at_logit_clamp_min():
    m = VoxelMap(0.5)
    values = []
    for _ in range(8):
        m.insert_scan([0.1, 0.1, 0.1], [[0.1, 0.1, 4.1]])
        values.append(m.log_odds([[0.1, 0.1, 2.1]])[0])
    assert values[1] == pytest.approx(2 * logit(0.4), abs=2 * TOL)
    assert values[-1] == pytest.approx(logit(0.12), abs=TOL) and min(values) >= logit(0.12) - TOL


def test_a_hit_after_misses_adds_to_the_clamped_value():
    m = VoxelMap(0.5)
    for _ in range(6):
        m.insert_scan([0.1, 0.1, 0.1], [[0.1, 0.1, 4.1]])
    m.insert_scan([0.1, 0.1, 0.1], [[0.1, 0.1, 2.1]])  # now the old path voxel is hit
    assert m.log_odds([[0.1, 0.1, 2.1]])[0] == pytest.approx(logit(0.12) + logit(0.7), abs=2 * TOL)


def test_custom_params_change_the_update():
    params = LogOddsParams(p_hit=0.9, p_miss=0.2, clamp_min=0.05, clamp_max=0.99)
    m = VoxelMap(0.5, params)
    m.insert_scan([0.1, 0.1, 0.1], [[0.1, 0.1, 4.1]])
    expected = [float(logit(0.9)), float(logit(0.2))]
    assert m.log_odds([[0.1, 0.1, 4.1], [0.1, 0.1, 2.1]]).tolist() == pytest.approx(expected, abs=params.quantum / 2)


def test_a_beam_carves_free_space_along_its_path_and_ends_occupied():
    m = VoxelMap(0.25)
    origin, end = np.array([0.3, -1.7, 2.05]), np.array([7.9, 4.2, 11.33])
    m.insert_scan(origin, [end])
    t = np.linspace(0.0, 1.0, 20001)[:, None]
    along = origin + t * (end - origin)
    before_end = np.any(np.floor(along / 0.25) != np.floor(end / 0.25), axis=1)
    assert (m.state(along[before_end]) == 0).all()
    assert m.state([end])[0] == 1
    assert m.known_voxels == len(reference_ray(origin, end, 0.25)) + 1
    off_path = along[before_end] + [0.0, 0.0, -1.0]
    assert (m.state(off_path[m.state(off_path) != 0]) == -1).all()


def test_a_beam_without_return_carves_free_space_only():
    m = VoxelMap(0.5)
    m.insert_scan([0.1, 0.1, 0.1], [[0.1, 0.1, 4.1], [2.1, 0.1, 4.1]], hit=[False, True])
    assert m.state([[0.1, 0.1, 2.1], [0.1, 0.1, 4.1], [2.1, 0.1, 4.1]]).tolist() == [0, -1, 1]


def test_beams_longer_than_max_range_are_cut_and_count_as_no_return():
    m = VoxelMap(0.5)
    m.insert_scan([0.1, 0.1, 0.1], [[0.1, 0.1, 10.1], [0.3, 0.1, 2.1]], max_range=5.0)
    assert m.state([[0.1, 0.1, 4.6], [0.1, 0.1, 5.6], [0.1, 0.1, 10.1], [0.3, 0.1, 2.1]]).tolist() == [0, -1, -1, 1]


def test_non_finite_endpoints_are_ignored():
    m = VoxelMap(0.5)
    m.insert_scan([0.1, 0.1, 0.1], [[np.nan, 0.0, 1.0], [0.1, 0.1, 2.1]])
    assert m.state([[0.1, 0.1, 2.1]])[0] == 1


def test_a_voxel_hit_and_passed_in_one_scan_counts_as_occupied_only():
    m = VoxelMap(1.0)
    # The first beam ends in voxel (0, 0, 3); the second passes straight through it on the way to (0, 0, 6).
    m.insert_scan([0.5, 0.5, 0.5], [[0.5, 0.5, 3.5], [0.5, 0.5, 6.5]])
    assert m.log_odds([[0.5, 0.5, 3.5]])[0] == pytest.approx(logit(0.7), abs=TOL)
    assert m.log_odds([[0.5, 0.5, 1.5]])[0] == pytest.approx(logit(0.4), abs=TOL)  # passed twice, updated once


def test_traversal_equals_a_step_by_step_reference_on_random_rays():
    rng = np.random.default_rng(4)
    resolution = 0.37
    for _ in range(20):
        origin = rng.uniform(-30, 30, 3)
        ends = origin + rng.normal(0, 1, (40, 3)) * rng.uniform(0.01, 25, (40, 1))
        beam, keys = ray_voxels(origin, ends, resolution)
        for i, end in enumerate(ends):
            ours = sorted(map(tuple, keys[beam == i].tolist()))
            assert ours == sorted(reference_ray(origin, end, resolution)), f"ray {origin} → {end}"


def test_one_scan_updates_exactly_the_reference_voxels():
    rng = np.random.default_rng(5)
    resolution = 0.3
    origin = np.array([10.0, -4.0, 20.0])
    ends = origin + rng.normal(0, 1, (300, 3)) * rng.uniform(0.05, 12, (300, 1))
    m = VoxelMap(resolution, block=8)
    m.insert_scan(origin, ends)
    hits = {tuple(k) for k in np.floor(ends / resolution).astype(int).tolist()}
    passed = {v for end in ends for v in reference_ray(origin, end, resolution)} - hits
    occupied = {tuple(k) for k in m.occupied_keys().tolist()}
    free = {tuple(k) for k in m.free_keys().tolist()}
    assert occupied == hits and free == passed and m.known_voxels == len(hits) + len(passed)


def test_a_flat_seabed_scanned_from_above_gives_its_depth_in_the_height_map():
    m = VoxelMap(0.25)
    depth = 40.13
    for north in np.arange(0.0, 30.0, 0.5):
        origin = np.array([north, 0.0, 20.0])
        m.insert_scan(origin, fan(origin, depth))
    heights = m.height_map((5.0, 25.0), (-30.0, 30.0), 0.5)
    assert heights.shape == (41, 121)
    seen = np.isfinite(heights)
    assert seen[:, 10:-10].all()  # a 120° swath from 20 m altitude reaches ±34 m across
    assert np.abs(heights[seen] - depth).max() <= 0.25
    assert np.isnan(m.height_map((100.0, 110.0), (0.0, 5.0), 1.0)).all()


def test_the_height_map_shows_the_top_of_a_box_on_the_seabed():
    m = VoxelMap(0.2)
    for north in np.arange(0.0, 20.0, 0.2):
        origin = np.array([north, 0.0, 10.0])
        ends = fan(origin, 30.0, beams=512)
        on_box = (np.abs(ends[:, 0] - 10.0) < 2.0) & (np.abs(ends[:, 1] - 3.0) < 1.5)
        ends[on_box, 2] = 28.0  # a 2 m tall box: its top is sensed at 28 m
        m.insert_scan(origin, ends)
    heights = m.height_map((0.0, 20.0), (-10.0, 10.0), 0.5)
    assert heights[20, 26] == pytest.approx(28.1, abs=0.11)  # (10 N, 3 E): the box top, voxel centre
    assert heights[20, 10] == pytest.approx(30.1, abs=0.11)  # (10 N, −5 E): the seabed
    counts = m.occupancy_projection((0.0, 20.0), (-10.0, 10.0), 0.5)
    assert counts.shape == heights.shape and counts[20, 26] >= 1 and counts[0, 0] >= 0
    best = m.occupancy_projection((0.0, 20.0), (-10.0, 10.0), 0.5, mode="max_probability")
    assert 0.5 <= best[20, 26] <= 0.97 + 1e-3


def test_storage_is_sparse_between_distant_scans():
    m = VoxelMap(0.25)
    m.insert_scan([0.0, 0.0, 20.0], fan([0.0, 0.0, 20.0], 40.0))
    one = m.store.count
    m.insert_scan([1000.0, 1000.0, 20.0], fan([1000.0, 1000.0, 20.0], 40.0))
    assert m.store.count == 2 * one  # the 1.4 km between the two pings holds no blocks, only the block index
    index_bytes = m.store.index.nbytes
    assert m.memory_bytes == 2 * one * 16**3 * 2 + index_bytes + 2 * one * 24 and index_bytes < 10e6


def test_a_300_by_400_m_survey_at_25_cm_with_a_20_m_water_column_fits_in_a_few_hundred_mb():
    # A coarse run over a 64 m wide strip measures the blocks per block column of a fully surveyed seabed
    # (vehicle at 20 m, seabed at 40 m, pings every 2 m, lines 32 m apart); the field needs that many per column.
    m = VoxelMap(0.25)
    for east in (0.0, 32.0):
        for north in np.arange(0.0, 64.0, 2.0):
            origin = np.array([north, east, 20.0])
            m.insert_scan(origin, fan(origin, 40.0, beams=512))
    store = m.store
    blocks = store.block_keys[: store.count]
    columns = len({(bx, by) for bx, by, _ in blocks.tolist()})
    block_m = store.block * m.resolution
    per_column = store.count * store.cells * store.pool.itemsize / columns
    field_bytes = per_column * (300 * 400) / block_m**2
    assert m.memory_bytes >= store.count * store.cells * 2
    assert field_bytes < 500e6, f"{field_bytes / 1e6:.0f} MB"


def test_octomap_labels_the_same_voxels_when_it_is_installed():
    octomap = pytest.importorskip("octomap")
    rng = np.random.default_rng(7)
    m, tree = VoxelMap(0.25), octomap.OcTree(0.25)
    for north in np.arange(0.0, 6.0, 0.3):
        origin = np.array([north + 0.01, 0.02, 10.0])
        ends = fan(origin, 25.0, beams=128)
        ends[:, 2] += rng.normal(0, 0.3, len(ends))
        m.insert_scan(origin, ends)
        tree.insertPointCloud(ends, origin, maxrange=-1.0)
    centres = np.concatenate([m.occupied_centres(), m.free_centres()])
    agree = np.mean(tree.getLabels(centres) == m.state(centres))
    assert agree > 0.999


def test_earlier_voxels_survive_the_index_growing_in_every_direction():
    rng = np.random.default_rng(8)
    m = VoxelMap(0.5, block=4)
    targets = []
    for _ in range(25):
        origin = rng.uniform(-200, 200, 3)
        end = origin + rng.normal(0, 5, 3)
        m.insert_scan(origin, [end])
        targets.append(end)
    assert (m.state(targets) == 1).all()


def test_endpoints_on_voxel_boundaries_land_in_the_voxel_a_query_names():
    # Multiples of 0.1 sit on (or a rounding error off) 0.1 m voxel boundaries; the map must store each return
    # in the same voxel that a query of that point finds, wherever the map's block index starts.
    m = VoxelMap(0.1)
    m.insert_scan([-500.03, 700.01, -3.0], [[-500.0, 700.0, 40.0]])
    ends = np.array([[0.2 * k, -0.1 * k, 30.0 + 0.1 * k] for k in range(40)])
    m.insert_scan([0.0, 0.0, 10.0], ends)
    assert (m.state(ends) == 1).all()
    assert len(m.occupied_keys()) == len(np.unique(m.keys(ends), axis=0)) + 1
