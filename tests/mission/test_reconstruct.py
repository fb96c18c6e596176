"""`auv reconstruct`: a run folder's KITTI-layout stereo recording (written by the simulator's recorder from pairs its
renderer made) becomes a mesh, glTF, points, a picture and a report, with the object where the truth has it."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "perception" / "reconstruction"))

from recon_views import Views, render_views  # noqa: E402

from mission.bench.reconstruction_scenes import SEABED_DEPTH, noisy_poses, truth_sdf  # noqa: E402
from mission.cli import main  # noqa: E402
from mission.plugin_api import StereoImages  # noqa: E402
from mission.reconstruct import ReconstructionError, read_recording, reconstruct_run  # noqa: E402
from mission.sim.stereo_record import StereoRecorder  # noqa: E402


def _named_targets(views: Views) -> dict[str, np.ndarray]:
    """True world positions of two features of the scene's wellhead: the tree's cap and the flowline stub's end."""
    tree, stub = views.parts[1], views.parts[2]
    return {"tree-cap": tree.T_world_part[:3, 3] - [0.0, 0.0, tree.half[2]],
            "stub-end": stub.T_world_part[:3, 3] + stub.T_world_part[:3, 0] * stub.half[0] - [0.0, 0.0, stub.half[2]]}


@pytest.fixture(scope="module")
def views() -> Views:
    return render_views(rings=((35.0, 5), (70.0, 2)))


@pytest.fixture(scope="module")
def run_dir(views: Views, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A run folder with the pairs recorded as an explore element would: truth in poses.txt, estimate in nav.txt."""
    run = tmp_path_factory.mktemp("run")
    nav = noisy_poses(views.poses, seed=3)
    with StereoRecorder(run / "models" / "wellhead-x") as recorder:
        for k, (frame, T, T_nav) in enumerate(zip(views.frames, views.poses, nav, strict=True)):
            images = StereoImages(float(k), frame.left, frame.right, frame.K, frame.baseline)  # type: ignore[attr-defined]
            recorder.write(images, T, T_nav)
    return run


def test_the_recording_is_read_with_the_estimated_poses(run_dir: Path, views: Views) -> None:
    recording = read_recording(run_dir / "models" / "wellhead-x")
    assert recording.pose_file == "nav.txt"
    assert len(recording.poses) == len(views.poses)
    assert recording.baseline == pytest.approx(0.25)
    assert not np.allclose(recording.poses[1], views.poses[1])  # the estimate, not the truth
    assert np.allclose(recording.poses[1][:3, 3], views.poses[1][:3, 3], atol=0.2)


def test_reconstruct_writes_a_mesh_on_the_true_object_and_its_files(run_dir: Path, views: Views) -> None:
    out = run_dir / "out"
    targets = [f"--target={name}={n},{e},{d}:2.5" for name, (n, e, d) in _named_targets(views).items()]
    # fx 400 at 5 m: a single view's depth σ is ~0.15 m, so no voxel would be sure to the default 6 cm.
    assert main(["reconstruct", str(run_dir), "--object", "wellhead-x", "--out", str(out), "--voxel", "0.05",
                 "--max-sigma", "0", *targets]) == 0
    for name in ("mesh.ply", "mesh.glb", "points.ply", "mesh.png", "report.json"):
        assert (out / name).stat().st_size > 500, name
    report = json.loads((out / "report.json").read_text())
    assert report["pose_file"] == "nav.txt" and report["frames"] == len(views.poses)
    # Seven views 50° apart around the object: the graph measures no motion between them and keeps navigation's.
    assert report["poses"] == "anchored" and report["graph"]["pairs_tried"] >= len(views.poses) - 1
    assert report["graph"]["moved_from_navigation_m"]["max"] < 0.01
    plane = report["seabed_plane"]
    # The flat seabed. At these small images (fx 400) the fused seabed comes out ~9 cm shallow (the range maps
    # alone are within 2 cm): a known shortfall, bounded here so that it cannot grow unnoticed.
    assert plane["c"] == pytest.approx(SEABED_DEPTH, abs=0.1)
    assert abs(plane["a"]) < 0.01 and abs(plane["b"]) < 0.01
    assert report["object_extent"]["height_m"] == pytest.approx(3.0, abs=0.25)  # the tree's top is 3 m up

    import trimesh

    mesh = trimesh.load(out / "mesh.ply", process=False)
    near = np.linalg.norm(mesh.vertices[:, :2], axis=1) < 3.5  # the object and the seabed at its foot
    err = np.abs(truth_sdf(views.parts, np.asarray(mesh.vertices[near])))
    assert np.median(err) < 0.05  # small images (fx 400) and navigation's pose noise
    glb = trimesh.load(out / "mesh.glb")
    assert sum(len(g.faces) for g in glb.geometry.values()) == len(mesh.faces)


def test_an_unknown_pose_source_is_refused_by_name(run_dir: Path) -> None:
    with pytest.raises(ReconstructionError, match="anchored, navigation"):
        reconstruct_run(run_dir, "wellhead-x", run_dir / "never", poses="nav")


def test_a_run_without_a_recording_is_refused_with_the_places_looked_at(tmp_path: Path) -> None:
    with pytest.raises(ReconstructionError, match="models/wellhead-x"):
        reconstruct_run(tmp_path, "wellhead-x")


def test_the_database_entry_is_accepted_by_the_mission_language(run_dir: Path, tmp_path: Path) -> None:
    import yaml

    from mission.language.loader import validate_mission_file

    entry = yaml.safe_load((run_dir / "out" / "object.yaml").read_text())["objects"][0]
    assert entry["id"] == "wellhead-x" and 1 <= len(entry["characteristic_points"]) <= 2
    assert all(4 <= len(s["points"]) <= 6 for s in entry["characteristic_points"])
    assert entry["pose"]["depth"] == pytest.approx(SEABED_DEPTH, abs=0.1)
    assert entry["size"][2] == pytest.approx(3.0, abs=0.25)
    assert entry["mesh"] == "mesh.ply"  # beside object.yaml; a mission names it relative to itself
    entry["mesh"] = str(run_dir / "out" / "mesh.ply")
    assert entry["model"] == "model/wellhead-x.yaml"  # the multi-view model, beside it
    entry["model"] = str(run_dir / "out" / "model" / "wellhead-x.yaml")
    mission = {"name": "uses-reconstruction", "objects": [entry],
               "sensors": {"usbl": {"sigma": 1.5}},
               "route": [{"id": "go", "transit": {"to": {"north": 0, "east": 0}, "depth": 20}}]}
    path = tmp_path / "m.yaml"
    path.write_text(yaml.safe_dump(mission, sort_keys=False))
    loaded, diagnostics = validate_mission_file(path)
    assert [d for d in diagnostics if not d.warning] == [] and loaded is not None
    assert loaded.objects[0].mesh == str(run_dir / "out" / "mesh.ply")
    assert loaded.objects[0].model == entry["model"]
    assert loaded.objects[0].characteristic_points[0].points[0] == pytest.approx(
        entry["characteristic_points"][0]["points"][0])


def test_named_targets_land_in_the_entry_at_their_true_world_positions(run_dir: Path, views: Views) -> None:
    import yaml

    entry = yaml.safe_load((run_dir / "out" / "object.yaml").read_text())["objects"][0]
    origin = np.array([entry["pose"][k] for k in ("north", "east", "depth")])
    assert entry["pose"]["heading"] == 0.0  # the entry's axes are the world's: the conversion is a shift
    centroids = {s["id"]: np.mean(s["points"], axis=0) for s in entry["characteristic_points"]}
    named = _named_targets(views)
    assert {t["id"] for t in entry["targets"]} == set(named)
    for target in entry["targets"]:
        assert origin + np.array(target["at"]) == pytest.approx(named[target["id"]], abs=1e-3)
        assert target["standoff"] == 2.5
        nearest = min(centroids, key=lambda k: float(np.linalg.norm(centroids[k] - np.array(target["at"]))))
        assert target["reference"] == nearest


def test_a_target_not_in_the_expected_form_is_refused_with_the_form() -> None:
    from mission.reconstruct import parse_target

    for text in ("valve=1,2", "=1,2,3", "valve=1,2,x", "valve=1,2,3:-1", "valve"):
        with pytest.raises(ReconstructionError, match="NAME=NORTH,EAST,DEPTH"):
            parse_target(text)


def test_an_entry_whose_mesh_is_not_a_mesh_is_refused_at_its_line(tmp_path: Path) -> None:
    from mission.language.loader import validate_mission_file

    (tmp_path / "notes.ply").write_text("these are notes\n")
    (tmp_path / "m.yaml").write_text(
        "name: m\nsensors: {usbl: {sigma: 1.5}}\nobjects:\n"
        "  - {id: a, pose: {north: 0, east: 0, depth: 30}, size: [1, 1, 1], mesh: notes.ply}\n"
        "  - {id: b, pose: {north: 5, east: 0, depth: 30}, size: [1, 1, 1], mesh: b.obj}\n"
        "route:\n  - {id: go, transit: {to: {north: 0, east: 0}, depth: 20}}\n")
    loaded, diagnostics = validate_mission_file(tmp_path / "m.yaml")
    messages = [str(d) for d in diagnostics if not d.warning]
    assert loaded is None and len(messages) == 2
    assert ":4:" in messages[0] and "not a PLY file" in messages[0]
    assert ":5:" in messages[1] and "not found" in messages[1]


def test_the_model_beside_the_entry_places_a_camera_in_the_entry_frame_where_the_recording_put_it(
        run_dir: Path, views: Views) -> None:
    import yaml

    from mission.frames import invert, pose_matrix
    from perception_plugins.multiview import recognise
    from perception_plugins.multiview.model_io import read_model

    report = json.loads((run_dir / "out" / "report.json").read_text())
    assert report["model"]["points"] > 200 and len(report["model"]["views"]) >= 2
    entry = yaml.safe_load((run_dir / "out" / "object.yaml").read_text())["objects"][0]
    model = read_model(run_dir / "out" / entry["model"])
    poses = np.loadtxt(run_dir / "out" / "camera_poses.txt").reshape(-1, 3, 4)
    T_world_db = pose_matrix(entry["pose"]["north"], entry["pose"]["east"], entry["pose"]["depth"], 0.0)
    k = int(model.views[0].name)  # a view of the model, recognised again through the model's own frame and tie
    T_world_cam = np.vstack([poses[k], [0.0, 0.0, 0.0, 1.0]])
    frame = views.frames[k]
    found = recognise(model, frame.left, frame.right, frame.K, frame.baseline, T_world_cam)
    assert found.identified and found.T_object_work is not None
    T_db_cam = model.T_database_object @ found.T_object_work
    expected = invert(T_world_db) @ T_world_cam
    assert np.linalg.norm(T_db_cam[:3, 3] - expected[:3, 3]) < 0.02
