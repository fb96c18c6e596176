"""The `explore` agent (seed 002 §2.2): gather the data for a model of an object the database lacks.

`planner: next-best-view` (§2.2.2, Fig. 6) scans a large object with the 3-D scanner:

1. approach: cruise at a depth clear of the object to above a safe starting view, picked in the safety grid of a
   voxel map seeded from the survey's height map (`explore_region.prior_map`), then descend onto it;
2. loop: scanner frames go into the voxel map at the *estimated* pose (`planners.nbv.NbvPlanner.integrate`;
   frames from nearly the same pose as the last are not fused: they cost as much and add little);
   at each view the planner proposes the next (candidates near the safe shell around the known structure, in
   free space, visibility by ray-casting the scanner frustum, the seed's utility with the mission's weights, the
   frontier and contour terms counted over the object's region until it has nothing left to reveal, then over
   the whole box: `FixedMountNbv`);
   the vehicle flies there on a safe path (`planners.nbv.connect`: straight when safe, else RRT* of
   `planners.rrt`), station keeping along it (`station_path.StationPath`) with the scanner pointed at the view's
   heading; a path that a later frame shows unsafe is abandoned and a new view proposed;
3. stop when the map's own estimate of the object's observed surface reaches `COVERAGE_TARGET` (`goal:
   reconstruct`: when the stereo camera has seen enough of the mapped surface well, `explore_stereo`), when no view
   would reveal anything, or when the element's budget (less the time to climb away) runs out; then climb back
   to the depth the element started at.

The scanner is fixed to the hull, tilted down (`mission.sim.scanner`): the vehicle turns to a view's heading, and
every view is planned with the mount's pitch, read from the frames' ray directions. The planning distance is the
mission's `safe_distance` plus `NAV_MARGIN_M` for the navigation error between the map and the truth.

`planner: rrt-photo` (§2.2.1) flies a photo survey of a flat object: `mission.agents.photo_survey`.
"""

from __future__ import annotations

import enum
import math
import time

import numpy as np

from mission.agents.base import Agent, AgentContext, Status
from mission.agents.explore_nbv import (
    RESOLUTION_M,
    FixedMountNbv,
    TargetRun,
    iteration_figures,
    mount_tilt_deg,
    nbv_results,
    path_safe,
    scan_of,
    target_run,
)
from mission.agents.explore_region import (
    targets,
)
from mission.agents.explore_stereo import add_pairs, camera_for, climb_clear, stereo_figures, target_reached
from mission.agents.report import ExploreReport
from mission.agents.station_path import StationPath
from mission.frames import wrap_deg
from mission.language.actions import EXPLORE_NAV_MARGIN_M
from mission.language.models import Explore
from mission.vehicle import Command, NavState, Observation, ScanFrame
from planners.nbv import UNKNOWN, NbvPlanner, Scanner, View, Weights, connect

PLANNING_RAYS = (24, 18)  # the planner's model of the frustum; the sensor itself has more rays
NAV_MARGIN_M = EXPLORE_NAV_MARGIN_M
COVERAGE_TARGET = 0.97
MAX_REJECTIONS = 10
HEADING_TOLERANCE_DEG = 6.0
CLIMB_RATE = 0.35  # m/s, a conservative figure for the time needed to climb away at the end
APPROACH_HANDOVER_M = 2.0  # cruising ends, station keeping begins, this far from the point above the start view
MIN_FRAME_MOVE_M = 0.4  # a frame is fused into the planner's map when the vehicle has moved or turned this much
MIN_FRAME_TURN_DEG = 5.0


class Phase(enum.Enum):
    """Where a next-best-view exploration is: the cruise and descent to the start view, the loop over views
    (move → settle → propose), and the climb away at the end."""

    APPROACH = "approach"  # cruise at a depth clear of the object, then descend onto the start view
    MOVE = "move"  # station keeping along the path to the next view
    SETTLE = "settle"  # at the view until the scanner faces its heading and a frame has been taken
    PROPOSE = "propose"  # the planner picks the next view
    LEAVE = "leave"  # climb back to the depth the element began at


class ExploreAgent(Agent):
    """Next-best-view scanning or a photo survey (`photo_survey.PhotoSurveyRun`) of the objects to explore."""

    kind = "explore"

    def start(self, context: AgentContext) -> None:
        p = context.element.explore
        assert p is not None
        self.params: Explore = p
        self.context = context
        self.t0 = context.nav.time
        self.exit_depth = context.nav.depth
        m = context.mission
        self.speed = m.vehicle.cruise_speed
        self.targets = targets(p.object, m, context.knowledge)
        self.runs: list[TargetRun] = []
        self.track: list[tuple[float, float, float, float]] = []
        self.details = self.report = ExploreReport(p.planner)
        context.emit("explore_sensor", context.nav.time, element=context.element.id, sensor=p.sensor, planner=p.planner)
        if p.planner == "rrt-photo":
            from mission.agents.photo_survey import PhotoSurveyRun

            self.photo: PhotoSurveyRun | None = PhotoSurveyRun(context, self.targets)
            self.payload = self.photo.payload
            return
        self.photo = None
        scanner = m.sensors.scanner
        if scanner is None:
            raise ValueError("explore with next-best-view needs `sensors.scanner`")
        self.model = Scanner((float(scanner.fov_deg[0]), float(scanner.fov_deg[1])), scanner.max_range,
                             PLANNING_RAYS)
        self.safe = p.safe_distance + NAV_MARGIN_M
        self.weights = Weights(p.weights.distance, p.weights.frontier, p.weights.contour)
        self.camera = camera_for(p, m)
        self.payload = frozenset({"scanner"} | ({"stereo"} if self.camera is not None else set()))
        self.tilt: float | None = None
        self.index = -1
        self.phase = Phase.APPROACH
        self.run: TargetRun | None = None
        self.path: StationPath | None = None
        self.goal: View | None = None
        self.aligned_at: float | None = None
        self.last_scan = -math.inf
        self.last_pose: tuple[float, float, float, float] | None = None
        self.rejections = 0
        if not self.targets:
            self.fail(f"no object to explore ('{p.object}': the survey found none the database lacks)"
                      if p.object == "detected" else f"no object '{p.object}' to explore")
            return
        self._next_target(context.nav)

    # -- set-up ------------------------------------------------------------------------------------------------
    def _next_target(self, nav: NavState, reason: str = "") -> None:
        if self.run is not None:
            self.run.stop_reason = self.run.stop_reason or reason
        self.index += 1
        if self.index >= len(self.targets):
            self._leave()
            return
        target = self.targets[self.index]
        self.cruise_depth = min(nav.depth, target.top_depth - self.safe - 1.0)
        run = target_run(target, self.context.knowledge, self.model, self.weights, self.safe, self.cruise_depth - 1.0,
                         self.context.mission.seed + self.index, (nav.north, nav.east),
                         self.tilt if self.tilt is not None else 25.0, camera=self.camera)
        self.runs.append(run)
        self.run = run
        if run.stop_reason:
            self.context.emit("explore_no_start", nav.time, element=self.context.element.id, object=target.id)
            self._next_target(nav)
            return
        self.phase = Phase.APPROACH
        self.rejections = 0

    def planned_path(self) -> list[tuple[float, float]]:
        if self.photo is not None:
            return self.photo.planned_path()
        return [(r.start.position[0], r.start.position[1]) for r in self.runs]

    # -- the loop ----------------------------------------------------------------------------------------------
    def step(self, observation: Observation) -> Command:
        nav = observation.nav
        if self.status is not Status.RUNNING:
            return Command.hold(nav)
        self.track.append((nav.time, nav.north, nav.east, nav.depth))
        if self.photo is not None:
            command = self.photo.step(observation)
            self.payload = self.photo.payload
            if self.photo.finished:
                self.succeed()
            return command
        for frame in observation.scans:
            self._integrate(frame)
        add_pairs(self.run, observation, self.phase is not Phase.LEAVE)
        budget_left = self.params.budget - (nav.time - self.t0)
        climb = max(0.0, nav.depth - self.exit_depth) / CLIMB_RATE + 15.0
        if self.phase is not Phase.LEAVE and budget_left <= climb:
            if self.run is not None:
                self.run.stop_reason = self.run.stop_reason or "budget"
            self._leave()
        here = np.array([nav.north, nav.east, nav.depth])
        if self.phase is Phase.APPROACH:
            return self._approach(nav, here)
        if self.phase is Phase.MOVE:
            return self._move(nav, here)
        if self.phase is Phase.SETTLE:
            return self._settle(nav, here)
        if self.phase is Phase.PROPOSE:
            return self._propose(nav, here)
        return self._climb(nav)

    def _integrate(self, frame: ScanFrame) -> None:
        if self.tilt is None:
            self.tilt = mount_tilt_deg(frame)
            for other in self.runs:
                other.planner.pitch_deg = -self.tilt
        run = self.run
        if run is None or self.phase is Phase.LEAVE:
            return
        # Frames from (nearly) the pose of the last one add little to the planner's map but cost as much: they
        # are skipped, except the first frame at a view. The metric `surface_observed_percent` counts every
        # frame the sensor took (the simulator logs their true hits), fused or not.
        pose = (frame.north, frame.east, frame.depth, frame.heading)
        wanted = self.phase is Phase.SETTLE and self.aligned_at is not None and self.last_scan <= self.aligned_at
        if self.last_pose is not None and not wanted:
            moved = math.dist(pose[:3], self.last_pose[:3])
            turned = abs(wrap_deg(pose[3] - self.last_pose[3]))
            if moved < MIN_FRAME_MOVE_M and turned < MIN_FRAME_TURN_DEG:
                return
        self.last_pose = pose
        run.planner.pitch_deg = -self.tilt
        t0 = time.perf_counter()
        run.planner.integrate(scan_of(frame))
        run.integrate_ms.append(1e3 * (time.perf_counter() - t0))
        grid = run.planner.grid
        run.volume.append((frame.time, float((grid.states != UNKNOWN).sum()) * grid.resolution**3, run.estimate))
        self.last_scan = frame.time
        # What a frame reveals can make the rest of the path unsafe; checked every other frame (1 s at 2 Hz, 30 cm
        # of travel at the hover speed), since it costs a distance transform of the safety grid.
        if self.phase is Phase.MOVE and self.path is not None and len(run.integrate_ms) % 2 == 0 \
                and not path_safe(run.planner, self.path.remaining(), self.safe):
            run.replans += 1
            self.phase = Phase.PROPOSE

    def _approach(self, nav: NavState, here: np.ndarray) -> Command:
        assert self.run is not None
        s = self.run.start.point
        distance = math.hypot(s[0] - nav.north, s[1] - nav.east)
        if distance > APPROACH_HANDOVER_M:
            heading = math.degrees(math.atan2(s[1] - nav.east, s[0] - nav.north)) % 360.0
            return Command(heading, self.speed, depth=self.cruise_depth)
        above = np.array([s[0], s[1], min(self.cruise_depth, s[2])])
        self._go(View.at(s, self.run.start.heading_deg, self.run.start.pitch_deg), np.stack([here, above, s]))
        return self._move(nav, here)

    def _go(self, view: View, points: np.ndarray) -> None:
        self.goal = view
        self.path = StationPath(points)
        self.phase = Phase.MOVE
        self.aligned_at = None

    def _move(self, nav: NavState, here: np.ndarray) -> Command:
        assert self.path is not None and self.goal is not None
        carrot = self.path.carrot(here)
        if self.path.done:
            self.phase = Phase.SETTLE
        return Command(self.goal.heading_deg, 0.0, depth=float(carrot[2]), station=(float(carrot[0]),
                                                                                      float(carrot[1])))

    def _hold(self) -> Command:
        assert self.goal is not None
        p = self.goal.point
        return Command(self.goal.heading_deg, 0.0, depth=float(p[2]), station=(float(p[0]), float(p[1])))

    def _settle(self, nav: NavState, here: np.ndarray) -> Command:
        """Hold the view until the scanner faces its heading and a frame has been taken there."""
        assert self.goal is not None and self.run is not None
        if self.aligned_at is None:
            if abs(wrap_deg(nav.heading - self.goal.heading_deg)) <= HEADING_TOLERANCE_DEG:
                self.aligned_at = nav.time
        elif self.last_scan > self.aligned_at:
            self.run.views.append((nav.time, nav.north, nav.east, nav.depth, nav.heading))
            self.phase = Phase.PROPOSE
        return self._hold()

    def _propose(self, nav: NavState, here: np.ndarray) -> Command:
        run = self.run
        assert run is not None and self.goal is not None
        t0, c0 = time.perf_counter(), time.process_time()
        run.estimate = run.coverage_estimate()
        if target_reached(self.context, run, nav.time, COVERAGE_TARGET):
            self._next_target(nav, "coverage target")
            return self._hold() if self.phase is not Phase.APPROACH else self._approach(nav, here)
        pose = View.at(here, nav.heading, -(self.tilt or 25.0))
        view = run.planner.propose(pose)
        if view is None and run.planner.focus is not None:
            # Nothing of the object's region is left unknown to a reachable view; spend what the budget leaves on
            # the whole box (views around the object from new sides add hits on its surface).
            run.planner.focus, run.planner.min_unknown = None, NbvPlanner.min_unknown
            run.focus_done_at = nav.time
            return self._hold()
        if view is None:
            self._next_target(nav, "nothing left to reveal")
            return self._hold() if self.phase is not Phase.APPROACH else self._approach(nav, here)
        path = connect(run.planner.safety, here, view.point, self.safe, seed=self.context.mission.seed)
        run.iterations_ms.append(1e3 * (time.perf_counter() - t0))
        run.iterations_cpu_ms.append(1e3 * (time.process_time() - c0))
        if path is None and (up := climb_clear(run, here, self.safe)) is not None:  # no path leaves the vehicle
            self._go(View.at(up, nav.heading, -(self.tilt or 25.0)), np.stack([here, up]))
            return self._move(nav, here)
        if path is None:
            run.planner.reject(view)
            run.rejected += 1
            self.rejections += 1
            if self.rejections >= MAX_REJECTIONS:
                self._next_target(nav, "no reachable view")
            return self._hold()
        self.rejections = 0
        self._go(view, path)
        return self._move(nav, here)

    def _leave(self) -> None:
        self.phase = Phase.LEAVE
        self.payload = frozenset()
        self.path = None

    def _climb(self, nav: NavState) -> Command:
        """Climb straight up to the depth the element began at (away from everything on the seabed)."""
        if not hasattr(self, "leave_at"):
            self.leave_at = (nav.north, nav.east)
        if nav.depth <= self.exit_depth + 0.5:
            self.succeed()
        return Command(nav.heading, 0.0, depth=self.exit_depth, station=self.leave_at)

    # -- results -----------------------------------------------------------------------------------------------
    def stop(self) -> None:
        if not hasattr(self, "params"):
            return
        if self.photo is not None:
            self.photo.finish(self.report)
            return
        objects, products = nbv_results(self.runs, self.t0)
        self.report.objects, self.report.views = objects, sum(len(r.views) for r in self.runs)
        self.report.resolution_m = RESOLUTION_M
        self.report.figures.update({**iteration_figures(self.runs), "safe_distance_m": self.params.safe_distance,
                                    "planning_distance_m": self.safe,
                                    "scanner_tilt_deg": round(self.tilt, 2) if self.tilt is not None else None})
        self.report.figures.update(stereo_figures(self.runs, self.context, self.params.goal))
        self.context.knowledge.maps[self.context.element.id] = {
            **products, "explore_track": np.asarray(self.track, dtype=np.float64).reshape(-1, 4),
            "explore_resolution": np.array(RESOLUTION_M)}


__all__ = ["COVERAGE_TARGET", "ExploreAgent", "FixedMountNbv", "NAV_MARGIN_M", "mount_tilt_deg", "scan_of"]
