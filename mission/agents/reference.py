"""The `reference` agent (seed 002 §3.1–3.3): hover above a known object's characteristic-point sets, take a
stereo pair, let the referencing plug-in identify a set and compute the camera's pose in the object frame;
when no set is recognised, move to the next position and try again.

Two stages. Search: positions are the centroids of the requested point sets placed with the database pose
(which may be metres off), each shifted by the element's `offsets`, at `search_altitude` for a wide view. Fine:
once a set is recognised, the vehicle hovers over that set's estimated centroid at `altitude`, turned so that
the image's long side runs along the object's x-axis, and references again with the now-good prior; that is the
element's result. Every attempt is recorded in `details["attempts"]` with the estimated camera pose, so that
metrics can score it against the truth.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from mission.agents.base import Agent, AgentContext
from mission.frames import camera_pose, invert, pose_matrix, transform_points, wrap_deg
from mission.language.models import KnownObject, Reference
from mission.plugin_api import PointSetModel, ReferencingRequest, ReferencingResult
from mission.vehicle import Command, Observation

ARRIVAL_M = 0.3  # horizontal distance (estimated) at which the vehicle counts as over its position
STATION_M = 4.0  # within this distance the vehicle station-keeps instead of cruising
DEPTH_TOLERANCE_M = 0.3
HEADING_TOLERANCE_DEG = 3.0
FINE_VIEWS = 3  # recognised views fused into the final referencing
FINE_SHIFT_M = 0.15  # successive fine views move this far along the object's x-axis
SEARCH_PRIOR_RADIUS_M = 4.0  # how far the database pose plus navigation may be off
FINE_PRIOR_RADIUS_M = 0.4  # how far a search-stage referencing may be off
VIEW_AGREEMENT_M = 0.04  # fine views whose transforms place the set's points this close agree


def database_pose(obj: KnownObject) -> np.ndarray:
    """T_world_object as the database has it (z parallel to the world z, per seed 000 §3.1)."""
    return pose_matrix(obj.pose.north, obj.pose.east, obj.pose.depth, obj.pose.heading)


class ReferenceAgent(Agent):
    kind = "reference"

    def start(self, context: AgentContext) -> None:
        p = context.element.reference
        assert p is not None
        self.params: Reference = p
        self.context = context
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
        self.fine: tuple[float, float, float, float] | None = None  # north, east, depth, heading
        self.fine_tries = 0
        self.T_world_object_est: np.ndarray | None = None
        self.views: list[tuple[np.ndarray, np.ndarray]] = []  # (model points, world points) of fine views
        # Near the object the DVL's relative navigation is steadier than acoustic fixes, whose updates would
        # shift the estimate between the views that are fused.
        self.navigation = "dead-reckoning"
        self.index = 0
        self.phase = "go"
        self.hold_since = math.nan
        self.attempts: list[dict[str, Any]] = []
        self.details = {"object": self.obj.id, "attempts": self.attempts}
        self.speed = min(context.mission.vehicle.cruise_speed, 1.0)
        if context.plugins is None or not context.plugins.has("referencing"):
            self.fail("no referencing plug-in is loaded")

    def planned_path(self) -> list[tuple[float, float]]:
        return [(n, e) for n, e, _, _ in self.positions]

    def _request(self, obs: Observation) -> tuple[ReferencingRequest, np.ndarray]:
        nav = obs.nav
        stereo = self.context.mission.sensors.stereo
        T_world_cam = camera_pose(nav.north, nav.east, nav.depth, nav.heading,
                                  baseline=stereo.baseline if stereo is not None else 0.0)
        T_world_object = self.T_world_object_est if self.T_world_object_est is not None else self.T_world_object_db
        prior = invert(T_world_cam) @ T_world_object
        # While searching, the prior is the database pose (metres off); once referenced, centimetres.
        radius = FINE_PRIOR_RADIUS_M if self.fine is not None else SEARCH_PRIOR_RADIUS_M
        return ReferencingRequest(self.models, prior, self.params.tolerance, radius), T_world_cam

    def _fine_pose(self, set_id: str) -> tuple[float, float, float, float]:
        """Hover over the recognised set's estimated centroid, image x along the object's x-axis."""
        assert self.T_world_object_est is not None
        pset = next(s for s in self.sets if s.id == set_id)
        points_world = transform_points(self.T_world_object_est, np.asarray(pset.points, dtype=float))
        x_axis = self.T_world_object_est[:3, 0]
        centre = points_world.mean(axis=0)
        object_heading = math.degrees(math.atan2(x_axis[1], x_axis[0]))
        return (float(centre[0]), float(centre[1]), float(points_world[:, 2].min()) - self.params.altitude,
                (object_heading - 90.0) % 360.0)

    def _attempt(self, obs: Observation) -> None:
        frame = obs.stereo[-1]
        request, T_world_cam = self._request(obs)
        assert self.context.plugins is not None
        t0 = time.perf_counter()
        result: ReferencingResult = self.context.plugins.process("referencing", frame, request, obs.nav.time)
        elapsed_ms = 1e3 * (time.perf_counter() - t0)
        record: dict[str, Any] = {
            "time": frame.time, "stage": "fine" if self.fine is not None else "search", "position": self.index,
            "recognised": bool(result.recognised),
            "set": result.set_id, "matched": int(result.matched), "residual_m": float(result.residual_rms),
            "ambiguous": bool(result.ambiguous), "cloud_points": int(result.cloud_points),
            "time_ms": round(elapsed_ms, 1), "T_world_cam_est": T_world_cam.round(6).tolist()}
        if result.recognised and result.T_cam_object is not None:
            T_object_cam = invert(result.T_cam_object)
            record["T_object_cam"] = T_object_cam.round(6).tolist()
            T_world_object = T_world_cam @ result.T_cam_object
            record["T_world_object_est"] = T_world_object.round(6).tolist()
        if result.details.get("reason"):
            record["reason"] = result.details["reason"]
        for key in ("approach", "elements", "table"):  # what a multi-view plug-in reports (seed 000 Table 1)
            if key in result.details:
                record[key] = result.details[key]
        self.attempts.append(record)
        self.context.emit("referencing_attempt", obs.nav.time, element=self.context.element.id,
                          **{k: v for k, v in record.items() if not k.startswith("T_") and k != "time"})
        if result.recognised and result.T_cam_object is not None:
            self.T_world_object_est = T_world_cam @ result.T_cam_object
            if self.fine is not None:
                if result.model_points is not None and result.points_cam is not None:
                    self.views.append((result.model_points, transform_points(T_world_cam, result.points_cam)))
                if len(self.views) >= FINE_VIEWS and self._fuse(T_world_cam, record):
                    self.succeed()
                    return
                north, east, depth, heading = self.fine
                shift = FINE_SHIFT_M * (1 if len(self.views) % 2 else -1)  # 0, +shift, 0, +shift ... along x
                x_axis = self.T_world_object_est[:3, 0]
                self.fine = (north + shift * float(x_axis[0]), east + shift * float(x_axis[1]), depth, heading)
                self.phase = "go"
                return
            self.fine = self._fine_pose(str(result.set_id))
            self.phase = "go"
            return
        if self.fine is not None and self.fine_tries < 2 * FINE_VIEWS:
            self.fine_tries += 1
            self.phase = "go"
            return
        self.fine, self.fine_tries, self.T_world_object_est, self.views = None, 0, None, []
        self.index += 1
        self.phase = "go"
        if self.index >= len(self.positions):
            self.fail(f"no point set of '{self.obj.id}' recognised in {len(self.attempts)} attempts")

    def _consistent_views(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """The largest group of fine views whose own transforms agree (a wrong identification that slipped
        through would otherwise pull the fused transform)."""
        from perception_plugins.referencing import rigid_transform

        probe = np.vstack([m for m, _ in self.views])
        placed = [transform_points(rigid_transform(m, w), probe) for m, w in self.views]
        agree = [[j for j in range(len(placed))
                  if float(np.max(np.linalg.norm(placed[i] - placed[j], axis=1))) <= VIEW_AGREEMENT_M]
                 for i in range(len(placed))]
        best = max(agree, key=len)
        return [self.views[j] for j in best]

    def _fuse(self, T_world_cam: np.ndarray, last: dict[str, Any]) -> bool:
        """One least-squares transform from the points of the agreeing fine views (seed 000, approach 3), placed
        in the world with the (dead-reckoned) estimate of each view; the camera pose of the last view in it.
        False while fewer than two views agree."""
        from perception_plugins.referencing import rigid_transform

        views = self._consistent_views()
        if len(views) < 2:
            return False
        model = np.vstack([m for m, _ in views])
        world = np.vstack([w for _, w in views])
        T_world_object = rigid_transform(model, world)
        self.T_world_object_est = T_world_object
        fused = {**{k: v for k, v in last.items() if not k.startswith("T_") and k not in ("elements", "table")},
                 "stage": "fused",
                 "matched": len(model), "views": len(views),
                 "residual_m": float(np.sqrt(np.mean(np.sum(
                     (transform_points(T_world_object, model) - world) ** 2, axis=1)))),
                 "T_object_cam": (invert(T_world_object) @ T_world_cam).round(6).tolist(),
                 "T_world_object_est": T_world_object.round(6).tolist()}
        self.attempts.append(fused)
        self.details["final"] = len(self.attempts) - 1
        return True

    def step(self, observation: Observation) -> Command:
        nav = observation.nav
        if self.index >= len(self.positions):
            return Command.hold(nav)
        if self.fine is not None:
            north, east, depth, final_heading = self.fine
        else:
            north, east, depth, _ = self.positions[self.index]
            final_heading = nav.heading
        distance = math.hypot(north - nav.north, east - nav.east)
        if self.phase == "go":
            aligned = abs(wrap_deg(nav.heading - final_heading)) <= HEADING_TOLERANCE_DEG
            if distance <= ARRIVAL_M and abs(nav.depth - depth) <= DEPTH_TOLERANCE_M and aligned:
                self.phase, self.hold_since = "settle", nav.time
            if distance > STATION_M:
                heading = math.degrees(math.atan2(east - nav.east, north - nav.north)) % 360.0
                return Command(heading, min(self.speed, max(0.3, 0.2 * distance)), depth=depth)
            return Command(final_heading, 0.0, depth=depth, station=(north, east))
        if self.phase == "settle":
            if nav.time - self.hold_since >= self.params.settle:
                self.phase = "capture"
                self.payload = frozenset({"stereo"})
            return Command(final_heading, 0.0, depth=depth, station=(north, east))
        # capture: the first frame that arrives is used
        if observation.stereo:
            self.payload = frozenset()
            self._attempt(observation)
        return Command(final_heading, 0.0, depth=depth, station=(north, east))
