"""Feasible viewpoints (issue 21 item 4): a target whose designed viewpoint breaks the altitude floor over what the
agent knows is photographed from the nearest feasible one (raised, or oblique with a tilted camera), planned from
the database and the altimeter, never the truth. The closed-loop tests fly the real simulated vehicle (kinematics,
navigation, altimeter noise, rendered camera) and score the photos against the truth."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from mission.agents.inspect.motion import Mover
from mission.agents.inspect.odometry import OdometryChain
from mission.agents.inspect.placement import Placement
from mission.agents.inspect.settings import InspectSettings
from mission.agents.inspect.surroundings import Surroundings
from mission.agents.inspect.targets import TargetVisit
from mission.agents.inspect.viewpoint import clearance, plan_viewpoint
from mission.agents.report import InspectReport, Photo, TargetOutcome
from mission.artifacts import Artifacts
from mission.frames import camera_pose, invert, transform_points
from mission.language import load_mission
from mission.language.models import Mission
from mission.language.mount import Mount
from mission.language.world import World
from mission.world.scene import Scene, build_scene

MIN_ALTITUDE = 1.5
FLOOR = MIN_ALTITUDE + InspectSettings().altitude_margin_m

# A skid (top at z = 0) with a 2 m module on it; a valve 0.6 m from the module's face, and a panel beside a bar
# that the database does not chart: under the vehicle (0.25 m starboard of the left camera, which looks at the
# panel; the vehicle heads west) but not between the camera and the panel. Object frame: x north, y east, z down;
# the object at 30 m, heading 0.
WORLD = """
name: viewpoint-bench
seabed: {north: [0, 40], east: [0, 40], resolution: 0.25, mean_depth: 30.5, texture: {kind: sand, seed: 5}}
objects:
  - id: rig
    database: rig
    pose: {north: 20, east: 20, depth: 30, heading: 0}
    parts:
      - {shape: box, size: [6, 6, 0.5], at: [3, 3, 0.25], color: [0.45, 0.38, 0.12]}
      - {shape: box, size: [2, 2, 2], at: [3, 4, -1.0], color: [0.95, 0.85, 0.3]}
      - {shape: box, size: [0.4, 0.4, 0.2], at: [3, 2.4, -0.1], color: [0.8, 0.1, 0.1]}
      - {shape: box, size: [0.4, 0.4, 0.2], at: [1, 1, -0.1], color: [0.2, 0.3, 0.7]}
      - {shape: box, size: [0.7, 1.6, 0.04], at: [1.45, 1.0, -0.58], color: [0.15, 0.35, 0.2]}
"""


def mission_with(tmp_path: Path, mount: str, home: tuple[float, float, float]) -> Mission:
    (tmp_path / "world.yaml").write_text(WORLD, encoding="utf-8")
    path = tmp_path / "mission.yaml"
    path.write_text(f"""
name: viewpoints
world: world.yaml
seed: 1
home: {{north: {home[0]}, east: {home[1]}, depth: {home[2]}}}
sensors:
  stereo: {{width: 320, height: 240, fx: 266.7, baseline: 0.5, rate_hz: 2, max_range: 8{mount}}}
  dvl: {{drift_percent: 0.5}}
plugins: {{referencing: stereo-referencing}}
safety:
  geofence: [[0, 0], [0, 40], [40, 40], [40, 0]]
  max_depth: 100
  min_altitude: {MIN_ALTITUDE}
objects:
  - id: rig
    pose: {{north: 20, east: 20, depth: 30, heading: 0}}
    size: [6, 6, 2.5]
    characteristic_points:
      - id: module-top
        points: [[2, 3, -2], [4, 3, -2], [4, 5, -2], [2, 5, -2], [3, 4, -2.0]]
    targets:
      - {{id: valve, at: [3, 2.4, -0.2], reference: module-top, standoff: 2.5, photos: 2}}
      - {{id: panel, at: [1, 1, -0.2], reference: module-top, standoff: 2.0, photos: 2}}
route:
  - id: look
    inspect: {{object: rig, targets: all}}
    actions: [photograph]
""", encoding="utf-8")
    return load_mission(path)


def fly(mission: Mission, tid: str) -> tuple[dict[str, Any], list[str], Any, Scene]:
    """Photograph one target with the real simulated vehicle (the object placed where the database says, which is
    where it lies); the photos scored against the truth (`mission.sim.inspect_metrics`)."""
    pytest.importorskip("mujoco")
    from mission.language.loader import load_world
    from mission.sim.inspect_metrics import inspect_truth
    from mission.sim.vehicle import SimulatedVehicle

    assert mission.world is not None
    world: World = load_world(mission.world)
    scene = build_scene(world)
    vehicle = SimulatedVehicle(mission, scene, seed=1)
    vehicle.set_payload(frozenset({"stereo"}))
    obj = mission.object("rig")
    stereo = mission.sensors.stereo
    assert stereo is not None
    T_wo = np.eye(4)
    T_wo[:3, 3] = (obj.pose.north, obj.pose.east, obj.pose.depth)
    place = Placement(T_wo.copy(), stereo.baseline, stereo.mount.tilt_deg)
    place.fix(T_wo.copy())
    settings = InspectSettings()
    events: list[str] = []
    records: list[dict[str, Any]] = []

    def emit(event: str, t: float, **fields: Any) -> None:
        events.append(event)
        records.append({"event": event, **fields})

    context = SimpleNamespace(artifacts=Artifacts(), element=SimpleNamespace(id="look"), emit=emit)
    done: list[str] = []
    stops = SimpleNamespace(photographed=lambda t, nav: done.append(t), odometry_lost=lambda t, nav: None)
    known = [np.asarray(ps.points, dtype=float) for ps in obj.characteristic_points]
    known += [np.asarray([t.at]) for t in obj.targets]
    mover = Mover(place, known, MIN_ALTITUDE, 0.5, settings)
    surroundings = Surroundings.of(known, FLOOR, place.tilt_deg, settings.max_range_ratio)
    target = next(t for t in obj.targets if t.id == tid)
    outcomes = {tid: TargetOutcome(target.photos, target.reference)}
    photos: list[Photo] = []
    visit = TargetVisit(context, {tid: target}, outcomes, photos, place, OdometryChain(None, place, settings),
                        mover, stops, surroundings, settings)  # type: ignore[arg-type]
    visit.begin(tid, 0.0)
    for _ in range(int(240 / vehicle.control_period)):
        observation = vehicle.observe()
        frame = observation.stereo[-1] if observation.stereo else None
        command = visit.step(observation.nav, frame)
        if done:
            break
        vehicle.apply(command)
        vehicle.advance()
    assert done == [tid], f"not photographed; events {events}"
    report = InspectReport("rig", [], 0.0, True, outcomes, photos=photos)
    truth = inspect_truth(report, vehicle, scene)
    truth["events"] = records
    truth["plan"] = visit.kind
    truth["measured"] = surroundings.measured
    return truth, events, vehicle, scene


def target_visible(vehicle: Any, scene: Scene, photo_time: float, target_object: np.ndarray) -> bool:
    """Render the camera where it truly was at the photo and check that the target's true position is in the
    image and is what the camera sees there (the depth buffer agrees: nothing in front of it)."""
    T_world_left = next(T for t, T in vehicle.log.frames if abs(t - photo_time) < 1e-6)
    truth = next(o for o in scene.objects if o.database == "rig")
    target_world = transform_points(truth.T_world_object, target_object[None, :])[0]
    p_cam = transform_points(invert(T_world_left), target_world[None, :])[0]
    vehicle.camera.depth = True  # the vehicle's camera skips the depth read-back; the test reads the truth
    frame = vehicle.camera.render(T_world_left)
    u = frame.K[0, 0] * p_cam[0] / p_cam[2] + frame.K[0, 2]
    v = frame.K[1, 1] * p_cam[1] / p_cam[2] + frame.K[1, 2]
    h, w = frame.depth_left.shape
    if not (p_cam[2] > 0 and 0 <= u < w and 0 <= v < h):
        return False
    return bool(abs(float(frame.depth_left[int(round(v)), int(round(u))]) - p_cam[2]) < 0.05)


def test_a_viewpoint_too_low_over_a_taller_part_is_raised_when_the_target_still_fits():
    target = np.array([10.0, 10.0, 30.0])
    taller = np.array([[10.0, 10.6, 29.6]])  # 0.4 m higher, 0.6 m beside the target
    plan = plan_viewpoint(target, 2.0, taller, FLOOR, 0.0, 90.0)
    assert plan.kind == "raised" and plan.feasible
    assert clearance(plan.camera, taller) >= FLOOR - 1e-9
    assert np.allclose(plan.camera, [10.0, 10.0, 29.6 - FLOOR])  # just as high as the floor needs, above it
    assert plan.range_m <= 2.0 * InspectSettings().max_range_ratio


def test_a_tilted_camera_photographs_obliquely_from_beside_a_target_too_close_to_a_tall_part():
    target = np.array([10.0, 10.0, 30.0])
    module = np.array([[10.0 + dx, 10.6 + dy, 28.2] for dx in (-1.0, 0.0, 1.0) for dy in (0.0, 1.0, 2.0)])
    plan = plan_viewpoint(target, 2.5, module, FLOOR, 270.0, 60.0)  # designed: looking west, from over the module
    assert plan.kind == "oblique" and plan.feasible and plan.range_m == 2.5
    assert clearance(plan.camera, module) >= FLOOR and plan.camera[1] < target[1]  # moved off the module's side
    axis = (target - plan.camera) / 2.5
    assert axis[2] == pytest.approx(np.sin(np.radians(60.0)))  # the tilted camera looks at the target


def test_the_default_mount_gives_the_camera_poses_of_the_down_looking_camera():
    down = Mount()
    pose = (12.3, -4.5, 56.7, 123.4, 1.5, -0.7)
    assert np.array_equal(camera_pose(*pose, baseline=0.25), camera_pose(*pose, baseline=0.25,
                                                                         R_body_cam=down.R_body_cam()))
    place = Placement(np.eye(4), 0.25)
    nav = SimpleNamespace(north=1.0, east=2.0, depth=3.0, heading=40.0)
    assert np.array_equal(place.camera_in_world(nav), camera_pose(1.0, 2.0, 3.0, 40.0, baseline=0.25))  # type: ignore[arg-type]
    tilted = Mount(tilt_deg=30.0).R_body_cam()
    assert np.allclose(tilted @ [0.0, 0.0, 1.0], [np.cos(np.radians(30)), 0.0, np.sin(np.radians(30))])


def test_a_target_beside_a_taller_part_is_photographed_from_a_feasible_oblique_viewpoint(tmp_path):
    mission = mission_with(tmp_path, ", mount: {tilt_deg: 60}", (20.0, 21.0, 25.5))
    truth, events, vehicle, scene = fly(mission, "valve")
    planned = [r for r in truth["events"] if r["event"] == "viewpoint_planned"]
    assert truth["plan"] == "oblique" and planned and planned[0]["feasible"]
    entry = truth["targets"]["valve"]
    assert entry["viewpoint"] == "oblique" and entry["ok"], entry
    for photo in truth["photos"]:
        assert photo["camera_error_m"] <= 0.1 and photo["target_in_image"]
        assert target_visible(vehicle, scene, photo["time"], np.array([3.0, 2.4, -0.2]))
    rows = np.array([r[:6] for r in vehicle.log.rows], dtype=float)
    assert rows[:, 5].min() >= MIN_ALTITUDE  # truly never under the minimum altitude
    assert entry["designed_error_max_m"] > 1.0  # the designed viewpoint, over the module, was not flown


def test_ground_the_altimeter_finds_under_a_viewpoint_raises_it_and_photos_come_from_there(tmp_path):
    mission = mission_with(tmp_path, "", (21.0, 21.0, 27.5))
    truth, events, vehicle, scene = fly(mission, "panel")
    replanned = [r for r in truth["events"] if r["event"] == "viewpoint_replanned"]
    assert replanned and replanned[-1]["kind"] == "raised"
    entry = truth["targets"]["panel"]
    assert entry["ok"], entry
    for photo in truth["photos"]:
        assert photo["camera_error_m"] <= 0.1 and photo["target_in_image"]
        assert target_visible(vehicle, scene, photo["time"], np.array([1.0, 1.0, -0.2]))
    rows = np.array([r[:6] for r in vehicle.log.rows], dtype=float)
    assert rows[-20:, 5].min() >= MIN_ALTITUDE  # over the tarpaulin, truly above the minimum altitude
