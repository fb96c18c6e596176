"""Target photography: the viewpoint `standoff` metres above the target with the camera looking down at it, the
vehicle held there until it settles, then the requested photos one interval apart, each with its pose."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
from doubles import frame_at, nav_at

from mission.agents.hover import Goal
from mission.agents.inspect.motion import Mover
from mission.agents.inspect.odometry import OdometryChain
from mission.agents.inspect.placement import Placement
from mission.agents.inspect.settings import InspectSettings
from mission.agents.inspect.surroundings import Surroundings
from mission.agents.inspect.targets import TargetVisit
from mission.agents.report import Photo, TargetOutcome
from mission.artifacts import Artifacts
from mission.frames import pose_matrix
from mission.geometry import transform_points
from mission.language.models import Target

T_WORLD_OBJECT = pose_matrix(150.0, 200.0, 58.0, 30.0)
HATCH = Target(id="hatch", at=(4.0, 2.5, -2.0), reference="module-top", standoff=3.0, photos=2)


def visit() -> tuple[TargetVisit, list[Photo], list[str], Placement]:
    place = Placement(T_WORLD_OBJECT.copy(), 0.25)
    place.fix(T_WORLD_OBJECT.copy())
    settings = InspectSettings()
    events: list[str] = []
    context = SimpleNamespace(artifacts=Artifacts(), element=SimpleNamespace(id="photograph"),
                              emit=lambda event, t, **fields: events.append(event))
    done: list[str] = []
    stops = SimpleNamespace(photographed=lambda tid, nav: done.append(tid), odometry_lost=lambda tid, nav: None)
    photos: list[Photo] = []
    mover = Mover(place, [np.asarray([HATCH.at])], 1.5, 1.0, settings)
    chain = OdometryChain(None, place, settings)
    surroundings = Surroundings.of([np.asarray([HATCH.at])], 1.5 + settings.altitude_margin_m, place.tilt_deg,
                                   settings.max_range_ratio)
    target_visit = TargetVisit(context, {"hatch": HATCH}, {"hatch": TargetOutcome(2, "module-top")}, photos, place,
                               chain, mover, stops, surroundings, settings)  # type: ignore[arg-type]
    target_visit.begin("hatch", 0.0)
    return target_visit, photos, done, place


def camera_at(goal: Goal, place: Placement) -> np.ndarray:
    return place.camera_in_world(nav_at(0.0, goal.north, goal.east, goal.depth, goal.heading))


def test_the_viewpoint_puts_the_camera_standoff_above_the_target_looking_down_along_the_object():
    target_visit, _, _, place = visit()
    T_world_cam = camera_at(target_visit.goal(), place)
    target_world = transform_points(T_WORLD_OBJECT, np.array([HATCH.at]))[0]
    assert np.allclose(T_world_cam[:3, 3], target_world + [0.0, 0.0, -3.0], atol=1e-9)
    assert np.allclose(T_world_cam[:3, 2], [0.0, 0.0, 1.0], atol=1e-9)  # the optical axis points down
    assert np.allclose(T_world_cam[:3, 0], T_WORLD_OBJECT[:3, 0], atol=1e-9)  # image x along the object's x


def test_photos_are_taken_after_settling_one_interval_apart_and_then_the_target_is_done():
    target_visit, photos, done, place = visit()
    goal = target_visit.goal()
    times = np.arange(0.0, 8.0, 0.2)
    for t in times:
        nav = nav_at(float(t), goal.north, goal.east, goal.depth, goal.heading, altitude=10.0)
        target_visit.step(nav, frame_at(float(t)))
        if done:
            break
    assert done == ["hatch"] and [p.index for p in photos] == [0, 1]
    assert photos[0].time >= 2.0 and photos[1].time - photos[0].time >= 1.0 - 1e-6
    assert all(p.camera_error_est_m < 1e-6 and not p.altitude_limited for p in photos)


def test_an_altimeter_that_forbids_the_viewpoint_keeps_the_vehicle_higher_and_says_so():
    target_visit, photos, done, place = visit()
    goal = target_visit.goal()
    # Something stands 1.5 m below the viewpoint (a tarpaulin over the hatch): with the minimum altitude of 1.5 m
    # and the 0.2 m margin, the vehicle may go no deeper than 0.2 m above the viewpoint.
    command = None
    for t in np.arange(0.0, 8.0, 0.2):
        nav = nav_at(float(t), goal.north, goal.east, goal.depth, goal.heading, altitude=1.5)
        command = target_visit.step(nav, frame_at(float(t)))
    assert command is not None and command.depth is not None and abs(command.depth - (goal.depth - 0.2)) < 1e-9
    assert target_visit.altitude_limited
