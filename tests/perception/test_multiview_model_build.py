"""`auv model build` on a run folder's stereo recording (KITTI layout): views chosen by proximity from the
navigation poses, the model written, read back and extended by a later run's views."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("MESA_SHADER_CACHE_DIR", tempfile.mkdtemp(prefix="mesa-cache-"))

import numpy as np  # noqa: E402
import pytest  # noqa: E402
import yaml  # noqa: E402

from mission.cli import main  # noqa: E402
from mission.geometry import invert  # noqa: E402
from mission.model_build import ModelBuildError, build_from_run  # noqa: E402
from mission.plugin_api import StereoImages  # noqa: E402
from perception_plugins.multiview.model_io import read_model  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]


def write_run(run: Path, frames: list, navs: list) -> None:
    """A run folder as `auv simulate --record-stereo` leaves it: mission.yaml and stereo/ (truth in poses.txt)."""
    from mission.sim.stereo_record import StereoRecorder

    doc = yaml.safe_load((ROOT / "missions" / "manifold_referencing.yaml").read_text())
    doc["world"] = str(ROOT / "worlds" / "sps_field.yaml")
    run.mkdir(parents=True, exist_ok=True)
    (run / "mission.yaml").write_text(yaml.safe_dump(doc, sort_keys=False))
    with StereoRecorder(run / "stereo") as rec:
        for k, (f, nav) in enumerate(zip(frames, navs, strict=True)):
            rec.write(StereoImages(0.1 * k, f.left, f.right, f.K, f.baseline), f.T_world_left, nav)


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory):
    from mission.bench.multiview import VIEW_SPACING_M, experiment
    from mission.sim.camera import RenderError

    try:
        exp = experiment(seed=5)
    except RenderError as exc:
        pytest.skip(f"no off-screen OpenGL here: {exc}")
    ax = exp.T_world_object[:3, 0]
    frames = []
    for s in np.arange(-6, 7) * 0.4 * VIEW_SPACING_M:                 # an overview pass, ~0.5 m between frames
        p = exp.roof + s * ax
        frames.append(exp.camera.render_at(p[0], p[1], exp.roof[2] - 4.5, exp.heading))
    first = tmp_path_factory.mktemp("overview")
    write_run(first, frames, [exp.nav(f.T_world_left) for f in frames])
    later = exp.inspection(2)
    second = tmp_path_factory.mktemp("inspection")
    write_run(second, later, [exp.nav(f.T_world_left) for f in later])
    yield exp, first, second, frames
    exp.camera.close()


def test_model_build_chooses_views_near_the_object_and_never_reads_the_truth(runs, capsys) -> None:
    exp, first, _, frames = runs
    # Corrupt the truth: a model that used it would change.
    truth = (first / "stereo" / "poses.txt").read_text()
    (first / "stereo" / "poses.txt").write_text(truth.replace("e+01", "e+02"))
    assert main(["model", "build", str(first), "--object", "manifold-1"]) == 0
    (first / "stereo" / "poses.txt").write_text(truth)
    out = capsys.readouterr().out
    path = first / "models" / "manifold-1.yaml"
    assert str(path) in out
    model = read_model(path)
    assert len(model.views) == 3
    # Chosen by proximity: the frame the navigation puts nearest the database centre, then others at least a
    # metre from it (the database pose is 2.3 m off the truth, so this is not the true centre frame).
    entry = yaml.safe_load((first / "mission.yaml").read_text())["objects"]
    pose = next(o for o in entry if o["id"] == "manifold-1")["pose"]
    navs = [v.T_world_view_nav[:3, 3] for v in model.views]
    heading = np.radians(pose["heading"])
    size = next(o for o in entry if o["id"] == "manifold-1")["size"]
    centre = np.array([pose["north"], pose["east"]]) + np.array(
        [[np.cos(heading), -np.sin(heading)], [np.sin(heading), np.cos(heading)]]) @ (np.array(size[:2]) / 2)
    dist = [float(np.linalg.norm(n[:2] - centre)) for n in navs]
    assert dist[0] == min(dist) and dist[0] <= 3.0   # the pass runs over the true roof, 2.3 m away
    assert min(np.linalg.norm(navs[i][:2] - navs[j][:2]) for i in range(3) for j in range(i)) >= 1.0
    # Each view's T_object_view agrees with the truth to millimetres (relative to the base view).
    base = model.views[0]
    T_world_object = frames[int(base.name)].T_world_left @ invert(base.T_object_view)
    for v in model.views[1:]:
        T_true = invert(T_world_object) @ frames[int(v.name)].T_world_left
        assert np.linalg.norm(T_true[:3, 3] - v.T_object_view[:3, 3]) <= 0.01
    # The object frame lies within the database object's frame where navigation puts it (z along world z).
    assert abs(model.T_database_object[2, 2] - 1.0) <= 1e-3


def test_a_later_run_extends_the_model_and_adds_its_views(runs) -> None:
    _, first, second, _ = runs
    model_path = first / "models" / "manifold-1.yaml"
    if not model_path.exists():
        build_from_run(first, "manifold-1")
    before = read_model(model_path)
    extended = second / "manifold-1.yaml"
    report = build_from_run(second, "manifold-1", views=[0, 1], out=extended, extend=model_path)
    after = read_model(extended)
    assert len(after.views) == len(before.views) + 2 and report.views[-2:] == ["000000", "000001"]
    assert len(after.points) > len(before.points)


def test_model_build_reports_a_missing_object_and_a_missing_recording(runs, tmp_path: Path, capsys) -> None:
    _, first, _, _ = runs
    with pytest.raises(ModelBuildError, match="no object 'wellhead-9'"):
        build_from_run(first, "wellhead-9")
    assert main(["model", "build", str(tmp_path), "--object", "manifold-1"]) == 1
    assert "no stereo recording" in capsys.readouterr().err
