"""The `reference` agent (seed 002 §3.1–3.3): hover above a known object's characteristic-point sets, take a
stereo pair, let the referencing plug-in identify a set and compute the camera's pose in the object frame;
when no set is recognised, move to the next position and try again.

Two stages. Search: positions are the centroids of the requested point sets placed with the database pose
(which may be metres off), each shifted by the element's `offsets`, at `search_altitude` for a wide view. Fine:
once a set is recognised, the vehicle hovers over that set's estimated centroid at `altitude`, turned so that
the image's long side runs along the object's x-axis, and references again with the now-good prior; the views
that agree are fused into the element's result (`mission.agents.fusion`). Every attempt is recorded in the
`ReferenceReport` with the estimated camera pose, so that metrics can score it against the truth.

Plug-in calls are asynchronous: the vehicle holds its station until the result of the frame it submitted
arrives, and uses it with the estimate of that frame's time.
"""

from __future__ import annotations

import enum
import math
import time
from typing import Any

import numpy as np

from mission.agents.base import Agent, AgentContext
from mission.agents.fusion import VIEW_AGREEMENT_M, View, fuse_views
from mission.agents.hover import WORK_SPEED_M_S, Goal, hover_command
from mission.agents.known_object import (
    FINE_PRIOR_RADIUS_M,
    FINE_SHIFT_M,
    FINE_VIEWS,
    SEARCH_PRIOR_RADIUS_M,
    attempt_record,
    database_pose,
)
from mission.agents.report import ReferenceReport
from mission.frames import camera_pose
from mission.geometry import invert, transform_points
from mission.language.models import Reference
from mission.language.mount import R_body_cam_of
from mission.plugin_api import PointSetModel, ReferencingRequest, ReferencingResult, StereoImages
from mission.plugin_calls import PluginCall
from mission.vehicle import Command, NavState, Observation

__all__ = ["ReferenceAgent", "database_pose"]


class Phase(enum.Enum):
    GO = "go"  # to the position (search) or the fine view
    SETTLE = "settle"  # there: let the vehicle settle for the element's `settle` seconds
    CAPTURE = "capture"  # the next stereo frame goes to the plug-in
    AWAIT = "await"  # the plug-in has the frame


class ReferenceAgent(Agent):
    """Search positions, then fine views over the recognised set, until the agreeing views are fused."""

    kind = "reference"

    def start(self, context: AgentContext) -> None:
        self.context = context
        p = context.element.reference
        assert p is not None  # the loader gives a `reference` element its settings
        self.params: Reference = p
        self.obj = context.mission.object(p.object)
        wanted = p.point_sets if isinstance(p.point_sets, list) else [s.id for s in self.obj.characteristic_points]
        self.sets = [s for s in self.obj.characteristic_points if s.id in wanted]
        self.models = tuple(PointSetModel(self.obj.id, s.id, np.asarray(s.points, dtype=float)) for s in self.sets)
        self.T_world_object_db = database_pose(self.obj)
        self.positions: list[tuple[float, float, float, str]] = []  # north, east, depth, set id
        for pset in self.sets:
            points_world = transform_points(self.T_world_object_db, np.asarray(pset.points, dtype=float))
            centre = points_world.mean(axis=0)
            top = float(points_world[:, 2].min())
            for dn, de in p.offsets:
                self.positions.append((float(centre[0] + dn), float(centre[1] + de), top - p.search_altitude,
                                       pset.id))
        self.fine: Goal | None = None
        self.fine_tries = 0
        self.T_world_object_est: np.ndarray | None = None
        self.views: list[View] = []  # (model points, world points) of fine views
        self.guided_views: list[View] = []  # ... of fine views that needed the plug-in's guided corners
        # Near the object the DVL's relative navigation is steadier than acoustic fixes, whose updates would
        # shift the estimate between the views that are fused.
        self.navigation = "dead-reckoning"
        self.index = 0
        self.phase = Phase.GO
        self.hold_since = math.nan
        self.pending: tuple[PluginCall, StereoImages, np.ndarray, float] | None = None
        self.details = self.report = ReferenceReport(self.obj.id)
        self.speed = min(context.mission.vehicle.cruise_speed, WORK_SPEED_M_S)
        stereo = context.mission.sensors.stereo
        self.baseline = stereo.baseline if stereo is not None else 0.0
        if context.plugins is None or not context.plugins.has("referencing"):
            self.fail("no referencing plug-in is loaded")

    def planned_path(self) -> list[tuple[float, float]]:
        return [(n, e) for n, e, _, _ in self.positions]

    def _submit(self, frame: StereoImages, nav: NavState) -> None:
        """Hand the frame to the plug-in with the prior of the object as estimated now: the database pose while
        searching (metres off), the search's referencing once a set is recognised (centimetres)."""
        T_world_cam = camera_pose(nav.north, nav.east, nav.depth, nav.heading, baseline=self.baseline,
                                  R_body_cam=R_body_cam_of(self.context.mission.sensors.stereo))
        T_world_object = self.T_world_object_est if self.T_world_object_est is not None else self.T_world_object_db
        prior = invert(T_world_cam) @ T_world_object
        radius = FINE_PRIOR_RADIUS_M if self.fine is not None else SEARCH_PRIOR_RADIUS_M
        request = ReferencingRequest(self.models, prior, self.params.tolerance, radius)
        assert self.context.plugins is not None
        call = self.context.plugins.submit("referencing", frame, request, nav.time)
        self.pending = (call, frame, T_world_cam, time.perf_counter())
        self.phase = Phase.AWAIT
        self._poll(nav)

    def _poll(self, nav: NavState) -> None:
        if self.pending is None:
            return
        call, frame, T_world_cam, started = self.pending
        result: ReferencingResult | None = call.poll(nav.time)
        if result is None:
            return
        self.pending = None
        self._attempt(result, frame, T_world_cam, 1e3 * (time.perf_counter() - started), nav)

    def _fine_pose(self, set_id: str) -> Goal:
        """Hover over the recognised set's estimated centroid, image x along the object's x-axis."""
        assert self.T_world_object_est is not None
        pset = next(s for s in self.sets if s.id == set_id)
        points_world = transform_points(self.T_world_object_est, np.asarray(pset.points, dtype=float))
        x_axis = self.T_world_object_est[:3, 0]
        centre = points_world.mean(axis=0)
        object_heading = math.degrees(math.atan2(x_axis[1], x_axis[0]))
        return Goal(float(centre[0]), float(centre[1]), float(points_world[:, 2].min()) - self.params.altitude,
                    (object_heading - 90.0) % 360.0)

    def _attempt(self, result: ReferencingResult, frame: StereoImages, T_world_cam: np.ndarray, elapsed_ms: float,
                 nav: NavState) -> None:
        record: dict[str, Any] = {
            "time": frame.time, "stage": "fine" if self.fine is not None else "search", "position": self.index,
            "set": result.set_id, **attempt_record(result), "time_ms": round(elapsed_ms, 1),
            "T_world_cam_est": T_world_cam.round(6).tolist()}
        if result.recognised and result.T_cam_object is not None:
            record["T_object_cam"] = invert(result.T_cam_object).round(6).tolist()
            record["T_world_object_est"] = (T_world_cam @ result.T_cam_object).round(6).tolist()
        if result.details.get("reason"):
            record["reason"] = result.details["reason"]
        for key in ("approach", "elements", "table"):  # what a multi-view plug-in reports (seed 000 Table 1)
            if key in result.details:
                record[key] = result.details[key]
        self.report.attempts.append(record)
        self.context.emit("referencing_attempt", nav.time, element=self.context.element.id,
                          **{k: v for k, v in record.items() if not k.startswith("T_") and k != "time"})
        self.phase = Phase.GO
        if result.recognised and result.T_cam_object is not None:
            self.T_world_object_est = T_world_cam @ result.T_cam_object
            if self.fine is None:
                self.fine = self._fine_pose(str(result.set_id))
                return
            if result.model_points is not None and result.points_cam is not None:
                view = (result.model_points, transform_points(T_world_cam, result.points_cam))
                (self.guided_views if result.details.get("guided") else self.views).append(view)
            if self._enough_views() and self._fuse(T_world_cam, record):
                self.succeed()
                return
            taken = len(self.views) + len(self.guided_views)
            shift = FINE_SHIFT_M * (1 if taken % 2 else -1)  # 0, +shift, 0, +shift ... along x
            x_axis = self.T_world_object_est[:3, 0]
            self.fine = Goal(self.fine.north + shift * float(x_axis[0]), self.fine.east + shift * float(x_axis[1]),
                             self.fine.depth, self.fine.heading)
            return
        if self.fine is not None and self.fine_tries < 2 * FINE_VIEWS:
            self.fine_tries += 1
            return
        self.fine, self.fine_tries, self.T_world_object_est, self.views, self.guided_views = None, 0, None, [], []
        self.index += 1
        if self.index >= len(self.positions):
            self.fail(f"no point set of '{self.obj.id}' recognised in {len(self.report.attempts)} attempts")

    def _enough_views(self) -> bool:
        """`FINE_VIEWS` views from the whole-image cloud; views that needed the plug-in's guided corners (less
        precise) count only once as many again have been taken."""
        return len(self.views) >= FINE_VIEWS or len(self.views) + len(self.guided_views) >= 2 * FINE_VIEWS

    def _fuse(self, T_world_cam: np.ndarray, last: dict[str, Any]) -> bool:
        """One least-squares transform from the points of the agreeing fine views (seed 000, approach 3), placed
        in the world with the (dead-reckoned) estimate of each view; the camera pose of the last view in it.
        False while fewer than two views agree."""
        views = self.views if len(self.views) >= FINE_VIEWS else self.views + self.guided_views
        fused = fuse_views(views, VIEW_AGREEMENT_M)
        if fused is None:
            return False
        self.T_world_object_est = fused.T
        self.report.attempts.append({
            **{k: v for k, v in last.items() if not k.startswith("T_") and k not in ("elements", "table")},
            "stage": "fused", "matched": fused.points, "views": fused.views, "residual_m": fused.residual_m,
            "T_object_cam": (invert(fused.T) @ T_world_cam).round(6).tolist(),
            "T_world_object_est": fused.T.round(6).tolist()})
        self.report.final = len(self.report.attempts) - 1
        return True

    def step(self, observation: Observation) -> Command:
        nav = observation.nav
        self._poll(nav)
        if self.index >= len(self.positions):
            return Command.hold(nav)
        if self.fine is not None:
            goal = self.fine
        else:
            north, east, depth, _ = self.positions[self.index]
            goal = Goal(north, east, depth, nav.heading)
        hold = Command(goal.heading, 0.0, depth=goal.depth, station=(goal.north, goal.east))
        if self.phase is Phase.GO:
            command, there = hover_command(nav, goal, self.speed)
            if there:
                self.phase, self.hold_since = Phase.SETTLE, nav.time
            return command
        if self.phase is Phase.SETTLE:
            if nav.time - self.hold_since >= self.params.settle:
                self.phase = Phase.CAPTURE
                self.payload = frozenset({"stereo"})
            return hold
        if self.phase is Phase.CAPTURE and observation.stereo:  # the first frame that arrives is used
            self.payload = frozenset()
            self._submit(observation.stereo[-1], nav)
        return hold
