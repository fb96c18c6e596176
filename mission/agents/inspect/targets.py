"""Target photography (seed 002 §3.4): from each target's viewpoint the requested photos, each saved with the
camera's estimated pose in the object frame. The designed viewpoint is `standoff` metres from the target along the
optical axis — above it, looking down, with the default mount — the image's long side along the object; when it
breaks the altitude floor over what the agent knows lies there (`surroundings`), the nearest feasible one is
planned (raised, or oblique with a tilted camera: `viewpoint`). While it settles at a viewpoint the vehicle
samples its altimeter; ground higher than known there becomes a known point, and the viewpoint is planned again.
The vehicle reaches the viewpoint by odometry; when the chain breaks, the target goes back in the queue behind a
re-referencing."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Protocol

import numpy as np

from mission.agents.base import AgentContext
from mission.agents.hover import Goal
from mission.agents.inspect.motion import Mover
from mission.agents.inspect.odometry import OdometryChain
from mission.agents.inspect.placement import Placement
from mission.agents.inspect.settings import InspectSettings
from mission.agents.inspect.states import Phase
from mission.agents.inspect.surroundings import PlannedView, Surroundings
from mission.agents.inspect.viewing import SetViewer
from mission.agents.report import Photo, TargetOutcome
from mission.geometry import transform_points
from mission.language.models import Target
from mission.plugin_api import StereoImages
from mission.vehicle import Command, NavState


class TargetStops(Protocol):
    """What a target visit tells the agent that sequences the stops."""

    def photographed(self, tid: str, nav: NavState) -> None: ...

    def odometry_lost(self, tid: str, nav: NavState) -> None: ...


class TargetVisit:
    """Photographing one target at a time (`begin`, then `step` every tick)."""

    def __init__(self, context: AgentContext, targets: Mapping[str, Target], outcomes: Mapping[str, TargetOutcome],
                 photos: list[Photo], place: Placement, chain: OdometryChain, mover: Mover, stops: TargetStops,
                 surroundings: Surroundings, settings: InspectSettings):
        self.context, self.targets, self.outcomes, self.photos = context, targets, outcomes, photos
        self.place, self.chain, self.mover, self.stops, self.settings = place, chain, mover, stops, settings
        self.surroundings = surroundings
        self.target_id = ""
        self.viewpoint = np.zeros(3)
        self.designed = np.zeros(3)  # the designed viewpoint (object frame), for reference
        self.kind = "designed"
        self.heading = 0.0
        self.replans = 0
        self.ground: list[tuple[float, float, float]] = []  # altimeter grounds while settling (north, east, depth)
        self.phase = Phase.GO
        self.hold_since = math.nan
        self.last_photo = -math.inf
        self.altitude_limited = False

    def begin(self, tid: str, now: float) -> None:
        target = self.targets[tid]
        up = self.place.T_wo[:3, :3].T @ np.array([0.0, 0.0, -1.0])  # the world's up, in the object frame
        self.target_id = tid
        self.designed = np.asarray(target.at, dtype=float) + target.standoff * up
        self.replans = 0
        self._plan(now, "planned")
        self.phase = Phase.GO
        self.last_photo = -math.inf
        # Whether the altimeter forbade the viewpoint's depth on the way (something under it stands higher than
        # the database says: a tarpaulin over a valve panel); the photos then come from the lowest safe depth,
        # and say so.
        self.altitude_limited = False

    def _plan(self, now: float, event: str) -> bool:
        """Plan the target's viewpoint from what is known now; True when it moved (and says so)."""
        target = self.targets[self.target_id]
        designed_heading = (self.place.heading() - 90.0) % 360.0
        view: PlannedView = self.surroundings.plan(target, self.place.T_wo, designed_heading)
        previous = self.viewpoint if event == "replanned" else self.designed
        if view.plan.kind == "designed":  # exactly the design (no round trip through the world frame)
            camera, heading = self.designed, designed_heading
        else:
            camera, heading = view.camera_object, view.heading_deg
        moved = bool(np.linalg.norm(camera - previous) > self.settings.viewpoint_replan_m) or event == "planned"
        if not moved:
            return False
        self.viewpoint, self.heading, self.kind = camera, heading, view.plan.kind
        outcome = self.outcomes[self.target_id]
        outcome.viewpoint_object = [round(float(x), 4) for x in self.viewpoint]
        outcome.designed_object = [round(float(x), 4) for x in self.designed]
        outcome.viewpoint = self.kind
        if self.kind != "designed":
            self.context.emit(f"viewpoint_{event}", now, element=self.context.element.id, target=self.target_id,
                              kind=self.kind, viewpoint_object=outcome.viewpoint_object,
                              designed_object=outcome.designed_object, heading_deg=round(heading, 2),
                              range_m=round(view.plan.range_m, 3), clearance_m=round(view.plan.clearance_m, 3),
                              feasible=view.plan.feasible)
        return True

    def _check_ground(self, nav: NavState) -> bool:
        """After settling: when the ground the altimeter saw is, on its median, too high for the viewpoint (the
        floor binds), keep it as known ground and plan again; True when the viewpoint moved (the vehicle goes
        there and settles again)."""
        s = self.settings
        samples, self.ground = np.asarray(self.ground, dtype=float), []
        if len(samples) < s.altimeter_samples or self.replans >= s.viewpoint_replans:
            return False
        viewpoint_depth = float(transform_points(self.place.T_wo, self.viewpoint[None, :])[0, 2])
        if float(np.median(samples[:, 2])) - viewpoint_depth >= self.surroundings.floor_m:
            return False
        self.surroundings.measure(self.place.T_wo, samples, s.altimeter_margin_m)
        if not self._plan(nav.time, "replanned"):
            return False
        self.replans += 1
        return True

    def goal(self) -> Goal:
        camera = transform_points(self.place.T_wo, self.viewpoint[None, :])[0]
        return SetViewer.camera_goal(self.place, camera, self.heading)

    def step(self, nav: NavState, frame: StereoImages | None) -> Command:
        s = self.settings
        if frame is not None:
            self.chain.feed(frame, nav)
            if self.chain.enabled and self.chain.broken:
                self.context.emit("odometry_lost", nav.time, element=self.context.element.id,
                                  target=self.target_id, lost_frames=self.chain.lost,
                                  reason="disagrees with navigation" if self.chain.disagrees else "tracking lost")
                self.stops.odometry_lost(self.target_id, nav)  # re-references first: the chain is broken
                return Command.hold(nav)
        goal = self.goal()
        over = math.hypot(goal.north - nav.north, goal.east - nav.east) <= s.over_goal_m
        if over and self.mover.altitude_floor(nav) < goal.depth - 0.01:
            self.altitude_limited = True
        slack = 1.0 if self.phase is Phase.GO else 2.0  # hysteresis: once there, noise must not send it back
        command, there = self.mover.go(nav, goal, slack * s.viewpoint_tolerance_m,
                                       slack * s.viewpoint_depth_tolerance_m)
        if self.phase is Phase.GO and there:
            self.phase, self.hold_since = Phase.SETTLE, nav.time
        elif self.phase is Phase.SETTLE:
            if not there:
                self.phase, self.ground = Phase.GO, []
            elif nav.time - self.hold_since >= s.settle_s:
                self.phase = Phase.GO if self._check_ground(nav) else Phase.PHOTO
            elif nav.altitude is not None:
                self.ground.append((nav.north, nav.east, nav.depth + nav.altitude))
        elif self.phase is Phase.PHOTO and frame is not None and there and \
                nav.time - self.last_photo >= s.photo_interval_s - 1e-6:
            self._photo(frame, nav)
        return command

    def _photo(self, frame: StereoImages, nav: NavState) -> None:
        tid = self.target_id
        outcome = self.outcomes[tid]
        k = outcome.photos
        element = self.context.element.id
        name = f"photos/{element}/{tid}_{k:02d}.png"
        self.context.artifacts.save_image(name, frame.left)
        T_object_cam = self.place.camera_in_object(nav)
        assert outcome.viewpoint_object is not None
        photo = Photo(tid, k, frame.time, name, outcome.viewpoint_object, T_object_cam.round(6).tolist(),
                      round(float(np.linalg.norm(T_object_cam[:3, 3] - self.viewpoint)), 4), self.altitude_limited,
                      round(self.chain.path_m, 3), [round(float(x), 4) for x in self.designed], self.kind)
        self.photos.append(photo)
        self.context.artifacts.append_record(f"photos/{element}/index.jsonl", photo.as_json())
        self.context.emit("photo", nav.time, element=element, target=tid, index=k, file=name,
                          camera_error_est_m=photo.camera_error_est_m, altitude_limited=photo.altitude_limited,
                          **({} if self.kind == "designed" else {"viewpoint": self.kind}))
        outcome.photos = k + 1
        self.last_photo = nav.time
        if outcome.done:
            self.stops.photographed(tid, nav)
