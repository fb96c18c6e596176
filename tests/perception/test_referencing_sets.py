"""Low, small point sets (issue 21 item 2): guided corners with the foreground's disparity, the skid sets
recognised on rendered views, and the detectability rating that `auv validate` shows."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np
import pytest

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("MESA_SHADER_CACHE_DIR", tempfile.mkdtemp(prefix="mesa-cache-"))

from mission.language.detectability import detectability_notes, rate_set  # noqa: E402
from mission.language.loader import load_mission  # noqa: E402
from mission.language.models import Stereo  # noqa: E402
from perception_plugins.referencing.guided import foreground_disparity  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
INSPECTION = ROOT / "docs" / "missions" / "manifold_inspection.yaml"
CAMERA = Stereo(width=1200, height=900, fx=1000.0, baseline=0.25, max_range=8.0)


def test_the_foreground_disparity_of_a_top_corner_is_the_parts_not_the_grounds() -> None:
    rng = np.random.default_rng(1)
    ground = rng.integers(0, 255, (120, 200)).astype(np.float32)
    part = rng.integers(0, 255, (120, 200)).astype(np.float32)
    left = ground.copy()
    left[60:, 100:] = part[60:, 100:]  # the part's top corner at (u, v) = (100, 60), ground everywhere else
    right = np.zeros_like(left)
    right[:, :-10] = ground[:, 10:]  # the ground 10 px of disparity, the part 16 px
    right[60:, 84:184] = part[60:, 100:]
    d = foreground_disparity(left.astype(np.uint8), right.astype(np.uint8), 100, 60, 5.0, 25.0)
    assert d is not None and abs(d[0] - 16.0) < 0.3


@pytest.mark.parametrize("set_id", ["skid-east", "skid-west", "module-top"])
def test_each_set_of_manifold_1_is_recognised_within_10_cm_in_its_rendered_fine_view(set_id: str) -> None:
    from mission.agents.inspect.placement import Placement
    from mission.agents.inspect.settings import InspectSettings
    from mission.agents.inspect.viewing import SetViewer
    from mission.frames import invert, pose_matrix, transform_points
    from mission.language.loader import load_world
    from mission.plugin_api import PointSetModel, ReferencingRequest, StereoImages
    from mission.sim.camera import StereoCamera
    from perception_plugins.referencing.plugin import StereoReferencingPlugin

    obj = load_mission(INSPECTION, environment=False).object("manifold-1")
    sets = {s.id: np.asarray(s.points, dtype=float) for s in obj.characteristic_points}
    with StereoCamera(load_world(ROOT / "worlds" / "sps_field.yaml"), CAMERA) as camera:
        truth = next(o for o in camera.world.scene.objects if o.id == "manifold-1").T_world_object
        viewer = SetViewer(sets, (1.2, 0.9), CAMERA.max_range, InspectSettings())
        goal = viewer.fine_goal(Placement(truth, CAMERA.baseline), set_id, 0)
        frame = camera.render_at(goal.north, goal.east, goal.depth, goal.heading)
    T_cam_object = invert(frame.T_world_left) @ truth
    prior = T_cam_object @ pose_matrix(0.06, -0.05, 0.04, 0.8)
    plugin = StereoReferencingPlugin()
    plugin.configure({"sensors": {"stereo": {"max_range": CAMERA.max_range}}})
    request = ReferencingRequest((PointSetModel("manifold-1", set_id, sets[set_id]),), prior, 0.05, 0.4)
    result = plugin.process(StereoImages(0.0, frame.left, frame.right, frame.K, frame.baseline), request)
    assert result.recognised and result.T_cam_object is not None, result.details
    error = np.linalg.norm(transform_points(result.T_cam_object, sets[set_id])
                           - transform_points(T_cam_object, sets[set_id]), axis=1)
    assert error.max() < 0.1


def test_a_tall_compact_set_rates_above_a_low_set_spread_across_a_skid() -> None:
    tall = rate_set("module-top", np.array([[2, 1, -2], [6, 1, -2], [6, 4, -2], [2, 4, -2], [4, 2.5, -2.6]]), CAMERA)
    low = rate_set("skid-east", np.array([[8, 0, 0], [8, 5, 0], [7, .5, -.3], [7, 4.5, -.3], [6.5, 2.5, -.4]]),
                   CAMERA)
    three = rate_set("three", np.array([[8, 0, 0], [8, 5, 0], [7, .5, -.3]]), CAMERA)
    assert tall.rating > low.rating > three.rating > 0
    assert low.view_range_m > tall.view_range_m and low.sigma_z_m > tall.sigma_z_m


def test_a_set_that_cannot_be_seen_whole_within_the_stereo_range_rates_zero() -> None:
    wide = rate_set("wide", np.array([[0, 0, 0], [9, 0, 0], [9, 6, 0], [0, 6, 0]]), CAMERA)
    assert wide.rating == 0 and "beyond the stereo range" in wide.reason
    assert rate_set("pair", np.array([[0, 0, 0], [1, 0, 0]]), CAMERA).rating == 0


def test_validate_notes_each_sets_detectability_at_its_line() -> None:
    mission = load_mission(INSPECTION, environment=False)
    notes = detectability_notes(INSPECTION, mission)
    lines = INSPECTION.read_text().splitlines()
    assert len(notes) == 3
    for note, set_id in zip(notes, ["module-top", "skid-east", "skid-west"], strict=True):
        line = int(note.split(":")[1])
        assert f"id: {set_id}" in lines[line - 1] and f"point set '{set_id}' detectability" in note
