"""Multi-view object models and three-stage recognition (seed 000 §3.1–3.2) against ground truth: the object frame
of Figure 2 on hand-built segments, segment lines on rendered pairs of the reference world checked against the
object's true edges, stage 2 with known poses, and recognition with 1–3 views."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("MESA_SHADER_CACHE_DIR", tempfile.mkdtemp(prefix="mesa-cache-"))

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from mission.geometry import invert, transform_points  # noqa: E402
from perception_plugins.multiview import (  # noqa: E402
    MultiviewError,
    RecognitionSettings,
    build_model,
    object_frame,
    parse_edits,
    recognise,
)
from perception_plugins.multiview.lines import recognise_lines  # noqa: E402
from perception_plugins.multiview.model_io import read_model, write_model  # noqa: E402
from perception_plugins.multiview.segments import stereo_segments  # noqa: E402
from perception_plugins.stereo.camera import RectifiedStereo  # noqa: E402
from perception_plugins.stereo.pipeline import stereo_cloud  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]


# --- Figure 2 -------------------------------------------------------------------------------------------------

def test_object_frame_follows_figure_2_on_a_hand_built_segment() -> None:
    # A camera tilted 20° about x: the world z-axis (down) seen from it is not the optical axis.
    tilt = np.radians(20.0)
    z_world_cam = np.array([0.0, np.sin(tilt), np.cos(tilt)])
    p1, p2 = np.array([0.3, -0.2, 4.0]), np.array([1.5, 0.4, 3.5])
    T_view_object = object_frame(p1, p2, z_world_cam)
    R = T_view_object[:3, :3]
    assert np.allclose(T_view_object[:3, 3], p1)                       # P1 is the origin
    assert np.allclose(R[:, 2], z_world_cam)                             # Z' along the external Z
    p2_proj = p2 - ((p2 - p1) @ z_world_cam) * z_world_cam               # P2' on the plane through P1 ⊥ Z'
    x_expected = (p2_proj - p1) / np.linalg.norm(p2_proj - p1)
    assert np.allclose(R[:, 0], x_expected)                              # X' along [P1, P2']
    assert np.allclose(R.T @ R, np.eye(3)) and np.isclose(np.linalg.det(R), 1.0)   # right-handed
    # In the object frame, P2 lies in the X'Z' plane at its height difference along Z'.
    p2_obj = transform_points(invert(T_view_object), p2[None])[0]
    assert p2_obj[1] == pytest.approx(0.0, abs=1e-12)
    assert p2_obj[0] == pytest.approx(np.linalg.norm(p2_proj - p1))
    assert p2_obj[2] == pytest.approx((p2 - p1) @ z_world_cam)


def test_object_frame_is_independent_of_the_camera_it_is_measured_in() -> None:
    rng = np.random.default_rng(4)
    p1_w, p2_w = np.array([10.0, 5.0, 50.0]), np.array([13.0, 7.0, 50.2])
    frames = []
    for _ in range(3):
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        q *= np.sign(np.linalg.det(q))
        T_world_cam = np.eye(4)
        T_world_cam[:3, :3], T_world_cam[:3, 3] = q, rng.normal(0, 3, 3)
        T_cam_world = invert(T_world_cam)
        p1_cam, p2_cam = transform_points(T_cam_world, np.stack([p1_w, p2_w]))
        T_view_object = object_frame(p1_cam, p2_cam, T_world_cam[2, :3])
        frames.append(T_world_cam @ T_view_object)                      # the object frame in the world
    assert np.allclose(frames[0], frames[1]) and np.allclose(frames[0], frames[2])


def test_a_vertical_base_segment_is_refused() -> None:
    with pytest.raises(MultiviewError, match="vertical"):
        object_frame([0.0, 0, 4], [0.0, 0, 3], [0.0, 0, 1])


def test_the_package_imports_no_mission_internals() -> None:
    import subprocess
    import sys

    code = ("import sys, perception_plugins.multiview, perception_plugins.multiview.model_io; "
            "bad = [m for m in sys.modules if m.split('.')[0] in ('mission', 'planners', 'mujoco') "
            "and m not in ('mission', 'mission.geometry')]; "
            "assert not bad, bad; import mission.plugin_api; contract = set(sys.modules); "
            "import perception_plugins.multiview.plugin; "
            "bad = [m for m in set(sys.modules) - contract if m.split('.')[0] in ('mission', 'planners')]; "
            "assert not bad, bad")
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT)


def test_malformed_edits_are_reported_with_their_place() -> None:
    with pytest.raises(MultiviewError, match=r"views.000010.add_edges\[0\]"):
        parse_edits({"views": {"000010": {"add_edges": [[1, 2]]}}})
    with pytest.raises(MultiviewError, match="unknown key"):
        parse_edits({"base": {"view": "a", "edge": [[0, 0], [1, 1]]}, "colour": 3})
    edits = parse_edits({"base": {"view": "000010", "edge": [[0, 0], [100, 2]]},
                         "views": {"000010": {"remove_points": [{"at": [5, 6], "radius": 30}]}}})
    assert edits.base_view == "000010" and edits.for_view("000010").remove_points[0][1] == 30


# --- rendered scenes ------------------------------------------------------------------------------------------

class Scene:
    def __init__(self) -> None:
        from mission.bench.multiview import experiment

        self.exp = experiment(seed=2)
        self.views, self.truth = self.exp.overview(3)
        self.model = build_model("manifold-1", self.views, T_world_database=self.exp.T_world_object)
        base = self.model.views[0]
        self.T_world_object_model = self.truth[base.name] @ invert(base.T_object_view)
        self.work = self.exp.inspection(3)


@pytest.fixture(scope="module")
def scene() -> Iterator[Scene]:
    from mission.sim.camera import RenderError

    try:
        s = Scene()
    except RenderError as exc:
        pytest.skip(f"no off-screen OpenGL here: {exc}")
    yield s
    s.exp.camera.close()


def box_edges_world(scene: Scene) -> np.ndarray:
    """(E, 2, 3) true edges of manifold-1's box parts in the world."""
    manifold = next(o for o in scene.exp.camera.world.scene.objects if o.id == "manifold-1")
    T_object_world = invert(manifold.T_world_object)
    edges = []
    for part in manifold.parts:
        c = np.asarray(part.corners_world)
        if len(c) != 8:
            continue
        local = transform_points(T_object_world, c)
        for i in range(8):
            for j in range(i + 1, 8):
                if np.sum(np.abs(local[i] - local[j]) > 1e-6) == 1:     # differ along one box axis: an edge
                    edges.append([c[i], c[j]])
    return np.array(edges)


def distance_to_edges(points: np.ndarray, edges: np.ndarray) -> np.ndarray:
    a, b = edges[:, 0], edges[:, 1]
    d = b - a
    t = np.clip(np.einsum("nek,ek->ne", points[:, None, :] - a[None], d) / np.sum(d * d, axis=1), 0, 1)
    closest = a[None] + t[..., None] * d[None]
    return np.min(np.linalg.norm(points[:, None, :] - closest, axis=2), axis=1)


def test_segment_lines_lie_on_the_objects_true_edges_with_their_face_on_the_right_side(scene: Scene) -> None:
    view = scene.views[1]
    T_world_left = scene.truth[view.name]
    geo = RectifiedStereo.from_K(view.K, view.baseline, (view.left.shape[1], view.left.shape[0]))
    segments = stereo_segments(view.left, view.right, geo)
    assert len(segments) >= 10
    ends = np.array([transform_points(T_world_left, s.points) for s in segments])
    dist = distance_to_edges(ends.reshape(-1, 3), box_edges_world(scene)).reshape(-1, 2)
    on_edges = np.all(dist <= 0.03, axis=1)
    assert on_edges.mean() >= 0.8, dist
    # Face side: the rendered depth just beside the edge on the face side equals the edge's depth.
    frame = scene.exp.camera.render(T_world_left)
    good = 0
    for s in segments:
        mid = s.uv_left.mean(axis=0)
        t = s.direction_2d
        n = s.side * np.array([-t[1], t[0]])
        u, v = np.rint(mid + 6 * n).astype(int)
        good += abs(float(frame.depth_left[v, u]) - float(s.points[:, 2].mean())) <= 0.05
    assert good >= 0.85 * len(segments)


def test_stage_2_recognises_lines_with_a_known_pose_and_not_with_a_wrong_one(scene: Scene) -> None:
    view = scene.model.views[1]
    frame = scene.work[1]
    geo = RectifiedStereo.from_K(frame.K, frame.baseline, (frame.left.shape[1], frame.left.shape[0]))
    T_world_view = scene.T_world_object_model @ view.T_object_view
    T_view_work = invert(T_world_view) @ frame.T_world_left
    found = recognise_lines(view, T_view_work, frame.left, frame.right, geo)
    ends = transform_points(invert(T_view_work), view.segment_points().reshape(-1, 3)) @ frame.K.T
    uv = (ends[:, :2] / ends[:, 2:]).reshape(-1, 2, 2)
    inside = np.all((uv[..., 0] > 30) & (uv[..., 0] < 1170) & (uv[..., 1] > 30) & (uv[..., 1] < 870), axis=1)
    assert len(found.segments) >= 0.5 * inside.sum() and len(found.segments) >= 5
    # Recognised end points are where the model's end points truly are, seen from the working camera.
    expected = transform_points(invert(T_view_work), found.view_points.reshape(-1, 3))
    err = np.linalg.norm(found.work_points.reshape(-1, 3) - expected, axis=1)
    assert np.median(err) <= 0.015 and np.percentile(err, 90) <= 0.05
    uv = expected @ frame.K.T
    assert np.median(np.linalg.norm(found.work_uv.reshape(-1, 2) - uv[:, :2] / uv[:, 2:], axis=1)) <= 1.5
    assert len(found.corners) >= 1
    # A transform 0.3 m off projects the edges beyond the search radius: they are not confirmed.
    shifted = T_view_work.copy()
    shifted[:3, 3] += [0.3, 0.0, 0.0]
    assert len(recognise_lines(view, shifted, frame.left, frame.right, geo).segments) <= 1


def work_cloud(frame: Any) -> Any:
    geo = RectifiedStereo.from_K(frame.K, frame.baseline, (frame.left.shape[1], frame.left.shape[0]))
    return stereo_cloud(frame.left, frame.right, geo, "sift", 1500, max_range=10.0)


def test_adding_views_never_lowers_the_matched_count_and_references_within_centimetres(scene: Scene) -> None:
    for frame in scene.work[::2]:
        T_true = invert(scene.T_world_object_model) @ frame.T_world_left
        counts, lines = [], []
        cloud = work_cloud(frame)
        for n in (1, 2, 3):
            r = recognise(scene.model, frame.left, frame.right, frame.K, frame.baseline, frame.T_world_left,
                          RecognitionSettings(views=n, approach="2b"), cloud=cloud)
            assert r.identified, r.reason
            assert len(r.table) == n
            counts.append(r.matched_points)
            lines.append(r.matched_lines)
            assert r.T_object_work is not None
            assert np.linalg.norm(r.T_object_work[:3, 3] - T_true[:3, 3]) <= 0.02
        assert counts == sorted(counts) and lines == sorted(lines)


def test_every_approach_references_the_camera_and_a_foreign_scene_is_not_identified(scene: Scene) -> None:
    frame = scene.work[1]
    T_true = invert(scene.T_world_object_model) @ frame.T_world_left
    cloud = work_cloud(frame)
    for approach in ("1", "2a", "2b", "3"):
        r = recognise(scene.model, frame.left, frame.right, frame.K, frame.baseline, frame.T_world_left,
                      RecognitionSettings(views=3, approach=approach), cloud=cloud)  # type: ignore[arg-type]
        assert r.identified and r.T_object_work is not None
        assert np.linalg.norm(r.T_object_work[:3, 3] - T_true[:3, 3]) <= 0.02, approach
    elsewhere = scene.exp.camera.render_at(scene.exp.roof[0] + 40.0, scene.exp.roof[1] - 30.0,
                                           scene.exp.roof[2] - 1.0, 10.0)
    r = recognise(scene.model, elsewhere.left, elsewhere.right, elsewhere.K, elsewhere.baseline)
    assert not r.identified and r.T_object_work is None


def test_a_model_written_and_read_back_recognises_alike(scene: Scene, tmp_path: Path) -> None:
    path = write_model(scene.model, tmp_path / "manifold-1.yaml")
    back = read_model(path)
    assert [v.name for v in back.views] == [v.name for v in scene.model.views]
    assert np.allclose(back.points, scene.model.points) and len(back.segments) == len(scene.model.segments)
    frame = scene.work[0]
    a = recognise(scene.model, frame.left, frame.right, frame.K, frame.baseline, frame.T_world_left)
    b = recognise(back, frame.left, frame.right, frame.K, frame.baseline, frame.T_world_left)
    assert a.table == b.table
    assert a.T_object_work is not None and b.T_object_work is not None
    assert np.allclose(a.T_object_work, b.T_object_work, atol=1e-9)


def test_the_full_model_averages_elements_seen_in_several_views(scene: Scene) -> None:
    model = scene.model
    total = sum(len(v.points) for v in model.views)
    assert len(model.points) < total                    # shared points merged
    shared = np.bincount(np.concatenate([v.point_ids for v in model.views]))
    assert np.sum(shared >= 2) >= 100
    # An averaged point is where the truth puts it (object frame of the model, true world poses).
    T_object_world = invert(scene.T_world_object_model)
    errs = []
    for v in model.views:
        T = T_object_world @ scene.truth[v.name]
        multi = shared[v.point_ids] >= 2
        errs.append(np.linalg.norm(model.points[v.point_ids[multi]] - transform_points(T, v.points[multi]), axis=1))
    assert np.median(np.concatenate(errs)) <= 0.03


def test_the_plug_in_references_the_camera_in_the_database_frame(scene: Scene, tmp_path: Path) -> None:
    from mission.plugin_api import PointSetModel, ReferencingRequest, StereoImages
    from perception_plugins.multiview.plugin import MultiviewReferencingPlugin

    path = write_model(scene.model, tmp_path / "manifold-1.yaml")
    plugin = MultiviewReferencingPlugin()
    plugin.configure({"multiview": {"models": {"manifold-1": str(path)}, "approach": "2b"}})
    frame = scene.work[2]
    T_db = scene.model.T_database_object
    T_object_work = invert(scene.T_world_object_model) @ frame.T_world_left
    prior = invert(T_db @ T_object_work)                      # T_cam_database, as the agent's prior would be
    prior[:3, 3] += [0.2, -0.1, 0.1]
    request = ReferencingRequest((PointSetModel("manifold-1", "any", np.zeros((3, 3))),), prior)
    result = plugin.process(StereoImages(0.0, frame.left, frame.right, frame.K, frame.baseline), request)
    assert result.recognised and result.T_cam_object is not None
    T_object_work_est = invert(T_db) @ invert(result.T_cam_object)
    assert np.linalg.norm(T_object_work_est[:3, 3] - T_object_work[:3, 3]) <= 0.02
    assert result.details["approach"] == "2b" and result.details["matched_lines"] >= 1
    assert result.model_points is not None and result.points_cam is not None
    assert len(result.model_points) == len(result.points_cam) >= result.matched
    with pytest.raises(MultiviewError, match="no multi-view model"):
        plugin.process(StereoImages(0.0, frame.left, frame.right, frame.K, frame.baseline),
                       ReferencingRequest((PointSetModel("wellhead-x", "any", np.zeros((3, 3))),), prior))


def test_an_operators_edits_pick_the_base_remove_and_add_points_and_edges(scene: Scene) -> None:
    from perception_plugins.multiview.formation import FormationSettings, view_elements

    view = scene.views[1]
    plain = view_elements(view, FormationSettings(), parse_edits(None).for_view(view.name))
    segments = plain[3]
    base, other = segments[2], segments[0]
    frame = scene.exp.camera.render(scene.truth[view.name])
    # A textured roof pixel away from every detected point, to add; a cluster of points, to remove.
    uv_pts = plain[1]
    candidates = np.array([[u, v] for u in range(300, 900, 37) for v in range(250, 650, 41)], dtype=float)
    gap = np.min(np.linalg.norm(candidates[:, None] - uv_pts[None], axis=2), axis=1)
    add = candidates[int(np.argmax(gap))]
    remove_at = uv_pts[0]
    edits = parse_edits({
        "base": {"view": view.name, "edge": base.uv_left.tolist()},
        "views": {view.name: {"remove_points": [{"at": remove_at.tolist(), "radius": 40}],
                              "add_points": [add.tolist()],
                              "remove_edges": [other.uv_left.mean(axis=0).tolist()],
                              "add_edges": [other.uv_left.tolist()]}}})
    model = build_model("manifold-1", [view], edits)
    v = model.views[0]
    assert np.allclose(model.base_segment[0], 0.0, atol=1e-9)                  # P1 of the picked edge is the origin
    assert np.linalg.norm(model.base_segment[1]) == pytest.approx(base.length, rel=1e-6)
    assert not np.any(np.linalg.norm(v.uv_left - remove_at, axis=1) <= 40)
    k = int(np.argmin(np.linalg.norm(v.uv_left - add, axis=1)))
    assert np.allclose(v.uv_left[k], add)
    u, w = np.rint(add).astype(int)
    assert v.points[k, 2] == pytest.approx(float(frame.depth_left[w, u]), abs=0.02)   # triangulated where it is
    assert len(v.segments) == len(segments)                                       # one removed, one added back
    readded = v.segments[-1]
    assert np.allclose(readded.uv_left, other.uv_left)
    assert np.max(np.linalg.norm(readded.points - other.points, axis=1)) <= 0.02
