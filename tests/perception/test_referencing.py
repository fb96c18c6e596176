"""Identification of characteristic points by structural coherence and referencing (seed 002 §3.1–3.3), against
known correspondences and known poses."""

import subprocess
import sys
import time
from itertools import combinations
from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy.spatial.transform import Rotation

from perception_plugins.referencing import (
    exhaustive_identify,
    identify,
    reference,
    rigid_transform,
    robust_rigid_transform,
)
from perception_plugins.referencing.anchors import triangle_plan
from perception_plugins.referencing.clique import dense_clique, maximal_cliques, maximum_cliques
from perception_plugins.referencing.consistency import all_pairs, consistency_graph, signature_candidates
from perception_plugins.referencing.transform import apply, rotation_angle_deg

ROOT = Path(__file__).resolve().parents[2]


def random_pose(rng, shift=5.0):
    T = np.eye(4)
    T[:3, :3] = Rotation.random(random_state=rng).as_matrix()
    T[:3, 3] = rng.uniform(-shift, shift, 3)
    return T


def box_surface(rng, lo, hi, count):
    """Points on the top and side faces of a box (z down: the top is z = lo[2])."""
    d = np.asarray(hi) - np.asarray(lo)
    face = rng.integers(0, 5, count)
    u, v = rng.random(count), rng.random(count)
    pts = np.empty((count, 3))
    pts[:, 0] = lo[0] + u * d[0]
    pts[:, 1] = lo[1] + v * d[1]
    pts[:, 2] = lo[2]
    for f, (axis, side) in enumerate([(0, lo[0]), (0, hi[0]), (1, lo[1]), (1, hi[1])], start=1):
        sel = face == f
        pts[sel, axis] = side
        pts[sel, 2] = lo[2] + rng.random(sel.sum()) * d[2]
    return pts


def surface_outliers(rng, model, count, lo=(0, 0, -1.5), hi=(8, 5, 0.5), seabed=0.5, keep_away=0.2):
    """Seabed-plane and object-surface points, none within `keep_away` of a model point."""
    out = []
    while sum(len(o) for o in out) < count:
        bed = np.column_stack([rng.uniform(lo[0] - 3, hi[0] + 3, count), rng.uniform(lo[1] - 3, hi[1] + 3, count),
                               np.full(count, seabed) + rng.normal(0, 0.03, count)])
        pts = np.vstack([bed[: count // 2], box_surface(rng, lo, hi, count - count // 2)])
        far = np.linalg.norm(pts[:, None] - model[None], axis=2).min(axis=1) >= keep_away
        out.append(pts[far])
    return np.concatenate(out)[:count]


def scene(seed, n_model, n_outliers, visible=None, sigma=0.01):
    """A model on an 8 × 5 × 2 m object, its visible part among surface outliers, in a random camera frame."""
    rng = np.random.default_rng(seed)
    model = box_surface(rng, (0, 0, -1.5), (8, 5, 0.5), 40 * n_model)
    keep = [model[0]]
    for p in model[1:]:
        if len(keep) < n_model and np.linalg.norm(np.array(keep) - p, axis=1).min() > 0.5:
            keep.append(p)
    model = np.array(keep)
    visible = n_model if visible is None else visible
    vis = np.sort(rng.permutation(n_model)[:visible])
    T = random_pose(rng)
    pts = np.vstack([model[vis], surface_outliers(rng, model, n_outliers)])
    cloud = apply(T, pts) + rng.normal(0, sigma, pts.shape)
    order = rng.permutation(len(cloud))
    where = np.argsort(order)
    truth = {int(k): int(where[i]) for i, k in enumerate(vis)}
    return model, cloud[order], truth, T


# --- the rigid transform ---------------------------------------------------------------------------------------

def test_rigid_transform_recovers_known_transforms():
    rng = np.random.default_rng(1)
    for _ in range(20):
        src = rng.normal(0, 3, (int(rng.integers(3, 30)), 3))
        T = random_pose(rng)
        assert rigid_transform(src, apply(T, src)) == pytest.approx(T, abs=1e-9)
        noisy = apply(T, src) + rng.normal(0, 0.01, src.shape)
        est = rigid_transform(src, noisy)
        assert rotation_angle_deg(est[:3, :3].T @ T[:3, :3]) < 2.0
        assert np.linalg.norm(apply(est, src) - noisy, axis=1).max() < 0.1


def test_rigid_transform_never_returns_a_reflection_even_for_mirrored_inputs():
    rng = np.random.default_rng(2)
    for _ in range(20):
        src = rng.normal(0, 2, (6, 3))
        mirrored = apply(random_pose(rng), src * [1, 1, -1])
        T = rigid_transform(src, mirrored)
        assert np.linalg.det(T[:3, :3]) == pytest.approx(1.0)
        assert T[:3, :3] @ T[:3, :3].T == pytest.approx(np.eye(3), abs=1e-9)
        assert np.linalg.norm(apply(T, src) - mirrored, axis=1).max() > 0.1     # a mirror cannot fit


def test_robust_rigid_transform_rejects_a_wrong_pair():
    rng = np.random.default_rng(3)
    src = rng.normal(0, 3, (10, 3))
    T = random_pose(rng)
    dst = apply(T, src) + rng.normal(0, 0.005, src.shape)
    dst[4] += [0.8, 0, 0]
    fit = robust_rigid_transform(src, dst, threshold=0.05)
    assert fit.inliers.tolist() == [k != 4 for k in range(10)]
    assert fit.T == pytest.approx(T, abs=0.02) and fit.rms < 0.02


# --- cliques ---------------------------------------------------------------------------------------------------

def planted(n, p, k, seed):
    rng = np.random.default_rng(seed)
    adj = rng.random((n, n)) < p
    adj = np.triu(adj, 1)
    adj = adj | adj.T
    members = rng.choice(n, k, replace=False)
    adj[np.ix_(members, members)] = True
    np.fill_diagonal(adj, False)
    return adj, sorted(members.tolist())


def test_maximum_cliques_finds_a_planted_clique_and_every_tie():
    adj, members = planted(150, 0.1, 9, seed=4)
    assert maximum_cliques(adj).cliques == [members]
    two = np.zeros((8, 8), dtype=bool)
    for group in ([0, 1, 2, 3], [4, 5, 6, 7]):
        two[np.ix_(group, group)] = True
    np.fill_diagonal(two, False)
    assert maximum_cliques(two).cliques == [[0, 1, 2, 3], [4, 5, 6, 7]]


def test_maximal_cliques_lists_every_maximal_clique_above_a_size():
    adj, members = planted(60, 0.15, 6, seed=5)
    found = maximal_cliques(adj, min_size=3)
    assert found.exact and found.cliques[0] == members
    assert all(len(a) >= len(b) for a, b in zip(found.cliques, found.cliques[1:], strict=False))
    for clique in found.cliques:
        sub = adj[np.ix_(clique, clique)]
        assert sub.sum() == len(clique) * (len(clique) - 1)                # a clique
        assert not np.any(np.all(adj[clique], axis=0))                     # and maximal


def test_exact_clique_search_stops_at_its_budget():
    adj, _ = planted(400, 0.5, 12, seed=6)                                  # dense: exponential for B&B
    t0 = time.perf_counter()
    result = maximum_cliques(adj, budget_s=0.2)
    assert time.perf_counter() - t0 < 1.0 and not result.exact


def test_dense_clique_fallback_is_polynomial_and_recovers_a_planted_clique():
    times = []
    sizes = [200, 400, 800, 1600]
    for n in sizes:
        adj, members = planted(n, 0.05, 30, seed=n)
        t0 = time.perf_counter()
        found = dense_clique(adj.astype(float), adj)
        times.append(time.perf_counter() - t0)
        assert found == members
        assert time.perf_counter() - t0 < 5.0
    slope = np.polyfit(np.log(sizes), np.log(times), 1)[0]
    assert slope < 3.0                                                      # O(iterations · k²) in theory


# --- consistency ------------------------------------------------------------------------------------------------

def test_signature_pruning_keeps_every_pair_of_the_true_identification():
    model, cloud, truth, _ = scene(7, 8, 60)
    from perception_plugins.referencing.consistency import distance_matrix

    kept = {tuple(p) for p in signature_candidates(distance_matrix(model), distance_matrix(cloud), 0.05, 5).tolist()}
    assert set(truth.items()) <= kept and len(kept) < 8 * len(cloud)


def test_the_true_identification_is_a_clique_of_the_consistency_graph():
    model, cloud, truth, _ = scene(8, 6, 20)
    g = consistency_graph(model, cloud, all_pairs(len(model), len(cloud)), tolerance=0.05)
    idx = [int(np.flatnonzero((g.nodes[:, 0] == k) & (g.nodes[:, 1] == j))[0]) for k, j in truth.items()]
    assert g.adjacency[np.ix_(idx, idx)].sum() == len(idx) * (len(idx) - 1)


def test_anchor_triangles_meet_every_set_of_their_level():
    for n in (8, 9, 12):
        order = np.random.default_rng(n).permutation(n)
        for level in range(n, 2, -1):
            plan = [set(t) for t in triangle_plan(order, level)]
            assert all(any(t <= set(s) for t in plan) for s in combinations(range(n), level)), (n, level)
            assert len(plan) <= len(triangle_plan(order, level - 1)) or level == 3


# --- identification ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("n_model,n_outliers,visible", [(6, 30, 5), (8, 120, 6), (12, 300, 9), (20, 480, 13)])
def test_identify_recovers_the_correct_pairs_among_noise_and_outliers(n_model, n_outliers, visible):
    for seed in range(4):
        model, cloud, truth, T = scene(100 + seed, n_model, n_outliers, visible, sigma=0.01)
        result = reference(model, cloud, tolerance=0.05)
        assert result.recognised
        assert set(result.pairs) <= set(truth.items())                     # no wrong pair
        assert len(result.pairs) >= min(visible, 3)
        assert rotation_angle_deg(result.T_cloud_model[:3, :3].T @ T[:3, :3]) < 1.0
        assert np.linalg.norm(result.T_cloud_model[:3, 3] - T[:3, 3]) < 0.1
        assert identify(model, cloud, tolerance=0.05) == result.pairs


def test_the_papers_exhaustive_search_agrees_with_identify_on_small_sets():
    agreed = 0
    for seed in range(25):
        rng = np.random.default_rng(seed)
        n_model, n_cloud = int(rng.integers(4, 7)), int(rng.integers(6, 11))
        visible = int(rng.integers(4, min(n_model, n_cloud) + 1))
        model = rng.uniform(0, 6, (n_model, 3))
        T = random_pose(rng)
        vis = rng.permutation(n_model)[:visible]
        pts = np.vstack([model[vis], rng.uniform(-2, 8, (n_cloud - visible, 3))])
        cloud = apply(T, pts) + rng.normal(0, 0.002, pts.shape)
        oracle = exhaustive_identify(model, cloud, tolerance=0.03)
        ours = identify(model, cloud, tolerance=0.03)
        assert ours == oracle, seed
        assert sorted(ours) == sorted((int(k), i) for i, k in enumerate(vis))
        agreed += 1
    assert agreed == 25


def test_a_mirrored_cloud_is_not_accepted_though_the_papers_search_accepts_it():
    rng = np.random.default_rng(11)
    model = rng.uniform(0, 6, (7, 3))
    cloud = apply(random_pose(rng), model * [1, 1, -1])                     # the mirror image
    cloud = np.vstack([cloud, rng.uniform(-5, 10, (8, 3))])
    assert len(exhaustive_identify(model, cloud, tolerance=0.02)) == 7      # distances alone cannot tell
    result = reference(model, cloud, tolerance=0.02)
    assert not result.recognised and result.pairs == []


def test_a_mirrored_cloud_among_many_outliers_is_not_accepted():
    model, cloud, truth, _ = scene(12, 12, 250)
    mirrored = cloud * [1, 1, -1]
    result = reference(model, mirrored, tolerance=0.05)
    assert len(set(result.pairs) & {(k, j) for k, j in truth.items()}) < 4


def test_fewer_than_three_matching_points_is_not_recognised():
    rng = np.random.default_rng(13)
    model = rng.uniform(0, 6, (6, 3))
    T = random_pose(rng)
    cloud = np.vstack([apply(T, model[:2]), rng.uniform(-20, 20, (6, 3))])
    result = reference(model, cloud, tolerance=0.02)
    assert not result.recognised and result.pairs == [] and result.T_cloud_model is None
    assert identify(model[:2], cloud, tolerance=0.02) == []


def test_collinear_three_point_sets_are_rejected():
    model = np.array([[0.0, 0, 0], [1, 0, 0], [2.5, 0.01, 0], [9, 9, 9]])
    cloud = model[:3] + [3.0, 4.0, 5.0]
    assert not reference(model, cloud, tolerance=0.05).recognised


def test_a_unique_three_point_set_is_recognised():
    model = np.array([[0.0, 0, 0], [3, 0, 0], [0, 4, 0], [9, 9, 9]])
    T = random_pose(np.random.default_rng(14))
    cloud = np.vstack([apply(T, model[:3]), [[50.0, 50, 50]]])
    result = reference(model, cloud, tolerance=0.02)
    assert result.recognised and result.pairs == [(0, 0), (1, 1), (2, 2)] and not result.ambiguous


def test_a_symmetric_rectangle_set_is_ambiguous_without_a_prior_and_resolved_with_one():
    module_top = np.array([[2, 1, -2], [6, 1, -2], [6, 4, -2], [2, 4, -2], [4, 2.5, -2.6]], dtype=float)
    rng = np.random.default_rng(15)
    T = random_pose(rng)
    half_turn = [2, 3, 0, 1, 4]                                              # what the other identification says
    truth = {k: k for k in range(5)}
    cloud = np.vstack([apply(T, module_top) + rng.normal(0, 0.005, (5, 3)), rng.uniform(-10, 10, (20, 3)) + 30])
    blind = reference(module_top, cloud, tolerance=0.03)
    assert blind.recognised and blind.ambiguous and blind.alternatives == 1
    assert set(blind.pairs) in ({(k, j) for k, j in truth.items()}, {(k, half_turn[k]) for k in range(5)})
    prior = T.copy()
    prior[:3, 3] += [1.5, -1.0, 0.5]                                         # a database pose off by metres
    prior[:3, :3] = Rotation.from_euler("z", 6, degrees=True).as_matrix() @ prior[:3, :3]
    guided = reference(module_top, cloud, tolerance=0.03, prior_T_cloud_model=prior)
    assert guided.recognised and not guided.ambiguous
    assert guided.pairs == sorted(truth.items())
    assert guided.T_cloud_model == pytest.approx(T, abs=0.02)
    sideways = T.copy()
    sideways[:3, :3] = T[:3, :3] @ Rotation.from_euler("z", 90, degrees=True).as_matrix()
    sideways[:3, 3] = T[:3, 3] + T[:3, :3] @ (np.array([4, 2.5, -2]) - sideways[:3, :3].T @ T[:3, :3]
                                              @ np.array([4, 2.5, -2]))
    torn = reference(module_top, cloud, tolerance=0.03, prior_T_cloud_model=sideways)
    assert torn.recognised and torn.ambiguous                               # 90° off: both halves equally far


def mission_sets():
    mission = yaml.safe_load((ROOT / "missions" / "sps_field_inspection.yaml").read_text())
    manifold = next(o for o in mission["objects"] if o["id"] == "manifold-1")
    return {s["id"]: np.array(s["points"], dtype=float) for s in manifold["characteristic_points"]}


@pytest.mark.parametrize("set_id", ["module-top", "skid-east", "skid-west"])
def test_the_reference_missions_point_sets_are_recognised_among_seabed_and_object_points(set_id):
    points = mission_sets()[set_id]
    for seed in range(3):
        rng = np.random.default_rng(seed)
        outliers = np.vstack([surface_outliers(rng, points, 60, lo=(0, 0, 0), hi=(8, 5, 0.5), seabed=0.5),
                              surface_outliers(rng, points, 40, lo=(2, 1, -2), hi=(6, 4, 0), seabed=0.5)])
        heading = Rotation.from_euler("z", rng.uniform(0, 360), degrees=True).as_matrix()
        T = np.eye(4)
        T[:3, :3] = heading.T
        T[:3, 3] = -heading.T @ np.array([4.0, 2.5, -5.5])                   # a camera 3.5 m above the module
        pts = np.vstack([points, outliers])
        cloud = apply(T, pts) + rng.normal(0, 0.01, pts.shape)
        prior = T.copy()
        prior[:3, 3] += rng.uniform(-2, 2, 3)
        result = reference(points, cloud, tolerance=0.05, prior_T_cloud_model=prior)
        assert result.recognised, (set_id, seed)
        assert result.pairs == [(k, k) for k in range(len(points))], (set_id, seed)
        assert not result.ambiguous
        assert np.linalg.norm(result.T_cloud_model[:3, 3] - T[:3, 3]) < 0.05


def test_the_anchored_search_agrees_with_the_full_graph_on_medium_sets(monkeypatch):
    import importlib

    module = importlib.import_module("perception_plugins.referencing.identification")
    for seed in range(5):
        model, cloud, truth, _ = scene(200 + seed, 8, 150, visible=6)
        monkeypatch.setattr(module, "FULL_GRAPH_PAIRS", 0)
        anchored = reference(model, cloud, tolerance=0.05)
        monkeypatch.setattr(module, "FULL_GRAPH_PAIRS", 10**6)
        full = reference(model, cloud, tolerance=0.05)
        assert anchored.method.startswith("anchored") and full.method == "full graph"
        assert anchored.pairs == full.pairs == sorted(truth.items())


def test_referencing_imports_nothing_of_mission_but_its_geometry_nor_planners():
    code = ("import sys, perception_plugins.referencing; "
            "bad = [m for m in sys.modules if m.split('.')[0] in ('mission', 'planners', 'mujoco') "
            "and m not in ('mission', 'mission.geometry')]; "
            "assert not bad, bad")
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT)


def test_the_polynomial_clique_fallback_still_identifies(monkeypatch):
    import importlib

    module = importlib.import_module("perception_plugins.referencing.identification")
    monkeypatch.setattr(module, "EXACT_CLIQUE_NODES", 0)
    model, cloud, truth, _ = scene(300, 12, 250, visible=9)
    result = reference(model, cloud, tolerance=0.05)
    assert "dense-clique fallback" in result.method and not result.exact
    assert result.pairs == sorted(truth.items())


def test_referencing_stays_within_its_time_budget_when_the_object_is_absent():
    rng = np.random.default_rng(17)
    model = rng.uniform(0, 8, (30, 3))
    cloud = surface_outliers(rng, model + 100.0, 1500)                      # seabed and faces, no model point
    t0 = time.perf_counter()
    result = reference(model, cloud, tolerance=0.05, budget_s=0.5)
    assert time.perf_counter() - t0 < 2.5
    assert not result.exact                                                 # it said it stopped early


def _plugin_result(monkeypatch, model, T_true, prior, set_id, radius):
    """The plug-in's answer when its stereo cloud is exactly the model placed at T_true (camera frame)."""
    from types import SimpleNamespace

    from mission.plugin_api import PointSetModel, ReferencingRequest, StereoImages
    from perception_plugins.referencing import plugin as plugin_module

    cloud = model @ T_true[:3, :3].T + T_true[:3, 3]
    monkeypatch.setattr(plugin_module, "stereo_cloud", lambda *a, **k: SimpleNamespace(points_cam=cloud))
    plugin = plugin_module.StereoReferencingPlugin()
    plugin.configure({})
    blank = np.zeros((90, 120), np.uint8)
    frame = StereoImages(0.0, blank, blank, np.array([[100.0, 0, 60], [0, 100, 45], [0, 0, 1]]), 0.25)
    return plugin.process(frame, ReferencingRequest((PointSetModel("m", set_id, model),), prior, 0.05, radius))


@pytest.mark.parametrize(("tilt_deg", "recognised"), [(2.0, True), (15.0, False)])
def test_the_plugin_refuses_a_fix_that_tilts_the_object_off_the_vertical(monkeypatch, tilt_deg, recognised):
    """A flat set can fit wrong correspondences by tilting; objects rest on the seabed, so a fix whose vertical
    axis leaves the prior's by more than the tilt gate (6°) is implausible, whatever its residual."""
    model = np.array([[0.0, 0, 0], [0, 5, 0], [1, 1.2, -0.3], [1.2, 4, -0.35], [0.5, 2.5, -0.2]])
    prior = np.eye(4)
    prior[:3, 3] = (-0.5, -2.5, 6.0)  # the set 6 m in front of a down-looking camera
    t = np.radians(tilt_deg)
    tilt = np.array([[np.cos(t), 0, np.sin(t)], [0, 1, 0], [-np.sin(t), 0, np.cos(t)]])
    T_true = prior.copy()
    T_true[:3, :3] = tilt
    result = _plugin_result(monkeypatch, model, T_true, prior, "skid", 0.4)
    assert result.recognised is recognised
    if recognised:
        np.testing.assert_allclose(result.T_cam_object, T_true, atol=1e-6)
    else:
        assert "tilted 15 deg" in result.details["reason"]


@pytest.mark.parametrize(("sink_m", "recognised"), [(0.4, True), (-0.4, True), (2.5, False), (-1.5, False)])
def test_the_plugin_refuses_a_fix_that_moves_the_object_up_or_down(monkeypatch, sink_m, recognised):
    """A module's top corners fit flat seabed texture too; such a fix sinks the object by its height. Structures
    rest on the seabed at the database's depth (within a metre), so a fix that moves the set along the prior's
    vertical by more than the depth gate (1 m) is implausible, while metres sideways are not."""
    model = np.array([[2.0, 1, -2], [6, 1, -2], [6, 4, -2], [2, 4, -2], [4, 2.5, -2.6]])
    yaw = np.radians(30.0)
    prior = np.eye(4)
    prior[:3, :3] = [[np.cos(yaw), -np.sin(yaw), 0], [np.sin(yaw), np.cos(yaw), 0], [0, 0, 1]]
    prior[:3, 3] = (-4.0, -2.5, 5.6)  # the object's top 3.6 m in front of a down-looking camera
    T_true = prior.copy()
    T_true[:3, 3] += (1.5, -1.0, sink_m)  # metres off sideways (allowed) and sink_m along the vertical
    result = _plugin_result(monkeypatch, model, T_true, prior, "module-top", 4.0)
    assert result.recognised is recognised
    if recognised:
        np.testing.assert_allclose(result.T_cam_object, T_true, atol=1e-6)
    else:
        word = "deeper" if sink_m > 0 else "shallower"
        assert f"{abs(sink_m):.1f} m {word} than the prior" in result.details["reason"]
