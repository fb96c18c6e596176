"""The simulated 3-D scanner (seed 002 §2.2.2) against geometry worked out by hand, and its agreement with the
view model the next-best-view planner uses."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mission.language.world import World
from mission.sim.mjworld import MjWorld
from mission.sim.scanner import Scanner3D
from mission.world.scene import build_scene
from planners.nbv import Box, Scanner, View
from planners.nbv import Scene as ViewScene

SEABED_DEPTH = 40.0
BOX = {"north": 20.0, "east": 0.0}  # a 4 × 4 × 3 m box on the seabed: north faces at 18 and 22, top at 37 m


@pytest.fixture(scope="module")
def world() -> MjWorld:
    w = World.model_validate({
        "name": "box",
        "seabed": {"north": [-60, 60], "east": [-60, 60], "resolution": 1.0, "mean_depth": SEABED_DEPTH,
                   "roughness": {"amplitude": 0.0}},
        "objects": [{"id": "block", "pose": {"north": BOX["north"], "east": BOX["east"], "depth": SEABED_DEPTH},
                     "parts": [{"shape": "box", "size": [4, 4, 3], "at": [0, 0, -1.5]}]}],
    })
    return MjWorld(build_scene(w))


def test_the_centre_ray_hits_the_box_face_at_the_distance_worked_out_by_hand(world: MjWorld) -> None:
    scanner = Scanner3D(world, (60.0, 45.0), 30.0, rays=(1, 1), tilt_deg=0.0, range_sigma=0.0)
    frame = scanner.scan(8.0, 0.0, 38.5, 0.0)  # level, 10 m south of the box's south face (north = 18)
    assert frame.hit[0] and frame.ranges[0] == pytest.approx(10.0, abs=1e-6)
    assert frame.object_ids[0] == "block"
    assert frame.true_points_ned[0] == pytest.approx([18.0, 0.0, 38.5], abs=1e-6)


def test_a_tilted_ray_hits_the_seabed_at_altitude_over_sine_of_the_tilt(world: MjWorld) -> None:
    scanner = Scanner3D(world, (60.0, 45.0), 60.0, rays=(1, 1), tilt_deg=30.0, range_sigma=0.0)
    frame = scanner.scan(-30.0, 0.0, 30.0, 180.0)  # looking south, away from the box, 10 m over the seabed
    assert frame.hit[0] and frame.object_ids[0] == ""
    assert frame.ranges[0] == pytest.approx(10.0 / math.sin(math.radians(30.0)), abs=1e-4)


def test_every_ray_matches_exact_ray_casting_of_the_same_geometry_in_the_planner_model(world: MjWorld) -> None:
    """The simulated frame equals the planner's own model of a view at heading h and pitch −tilt."""
    scanner = Scanner3D(world, (60.0, 45.0), 12.0, rays=(16, 12), tilt_deg=25.0, range_sigma=0.0)
    view = View.at((10.0, -3.0, 33.0), heading_deg=15.0, pitch_deg=-25.0)
    frame = scanner.scan(*view.position, view.heading_deg)
    exact = ViewScene(boxes=(Box((18.0, -2.0, 37.0), (22.0, 2.0, 40.0)),), seabed_depth=SEABED_DEPTH)
    expected = exact.scan(view, Scanner((60.0, 45.0), 12.0, (16, 12)))
    assert 0 < frame.hit.sum() < frame.hit.size  # some rays reach the box or seabed, some run out of range
    assert np.array_equal(frame.hit, expected.hit)
    ends = frame.true_points_ned[frame.hit]
    assert np.allclose(ends, expected.endpoints[expected.hit], atol=1e-4)
    assert np.all(ends[:, 2] <= SEABED_DEPTH + 1e-6)


def test_range_noise_has_the_configured_spread(world: MjWorld) -> None:
    scanner = Scanner3D(world, (20.0, 10.0), 30.0, rays=(20, 20), tilt_deg=0.0, range_sigma=0.02, seed=3)
    frame = scanner.scan(8.0, 0.0, 38.5, 0.0)
    hit = frame.hit
    exact = np.linalg.norm(frame.true_points_ned[hit] - frame.origin_ned, axis=1)
    err = frame.ranges[hit] - exact
    assert hit.all()
    assert abs(float(err.mean())) < 0.006 and float(err.std()) == pytest.approx(0.02, rel=0.25)


def test_a_scanner_following_the_vehicle_sees_the_reference_world_as_the_full_model_does() -> None:
    """The cropped seabed (`LocalWorld`) gives the same ranges as the whole world, in and after a re-crop."""
    from pathlib import Path

    from mission.language.loader import load_world
    from mission.sim.scanner import LocalWorld

    scene = build_scene(load_world(Path(__file__).resolve().parents[3] / "worlds" / "sps_field.yaml"))
    full = Scanner3D(MjWorld(scene), range_sigma=0.0)
    local = Scanner3D(LocalWorld(scene, 12.0), range_sigma=0.0)
    for north, east, heading in ((205.0, 110.0, 0.0), (225.0, 118.0, 200.0), (290.0, 40.0, 90.0)):
        a, b = full.scan(north, east, 51.0, heading), local.scan(north, east, 51.0, heading)
        assert a.hit.sum() > 100 and np.array_equal(a.hit, b.hit)
        assert np.allclose(a.ranges[a.hit], b.ranges[b.hit], atol=1e-6)
        assert np.array_equal(a.object_ids, b.object_ids)
