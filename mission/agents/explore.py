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
3. stop when the map's own estimate of the object's observed surface reaches `COVERAGE_TARGET`, when no view
   would reveal anything, or when the element's budget (less the time to climb away) runs out; then climb back
   to the depth the element started at.

The scanner is fixed to the hull, tilted down (`mission.sim.scanner`): the vehicle turns to a view's heading, and
every view is planned with the mount's pitch, read from the frames' ray directions. The planning distance is the
mission's `safe_distance` plus `NAV_MARGIN_M` for the navigation error between the map and the truth.

`planner: rrt-photo` (§2.2.1) flies a photo survey of a flat object: `mission.agents.photo_survey`.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from mission.agents.base import Agent, AgentContext, Status
from mission.agents.explore_region import (
    Target,
    exploration_box,
    prior_map,
    seabed_depth,
    survey_map_for,
    targets,
)
from mission.agents.station_path import StationPath
from mission.frames import rotation_zyx, wrap_deg
from mission.language.models import Explore
from mission.vehicle import Command, NavState, Observation, ScanFrame
from planners.nbv import NbvPlanner, Scan, Scanner, View, Views, Weights, connect, segment_safe
from planners.nbv.candidates import is_safe_view
from planners.nbv.grid import FREE, UNKNOWN, StateGrid

RESOLUTION_M = 0.25
PLANNING_RAYS = (24, 18)  # the planner's model of the frustum; the sensor itself has more rays
NAV_MARGIN_M = 1.0
COVERAGE_TARGET = 0.97
MAX_REJECTIONS = 10
HEADING_TOLERANCE_DEG = 6.0
CLIMB_RATE = 0.35  # m/s, a conservative figure for the time needed to climb away at the end
APPROACH_HANDOVER_M = 2.0
PRIOR_UNCERTAIN_M = 0.5  # the survey's soundings are 0.5 m cell means: the last 0.5 m above them stays unknown
MIN_UNKNOWN = 4  # a view that would reveal fewer unknown voxels of the object's region is not worth the move
FOCUS_MARGIN_M = 1.5  # the object's region: its footprint's circle and its height grown by this much
MIN_FRAME_MOVE_M = 0.4  # a frame is fused into the planner's map when the vehicle has moved or turned this much
MIN_FRAME_TURN_DEG = 5.0  # cruising ends, station keeping begins, this far from the point above the start view


@dataclass
class FixedMountNbv(NbvPlanner):
    """`NbvPlanner` for a scanner fixed to the hull: every candidate has the mount's pitch (the vehicle can turn
    to any heading but keeps its pitch).

    With a `focus` (a boolean mask over the state grid: the object's region), the frontier and contour terms count
    the object only: unknown voxels outside the focus (the seabed's shadows around it, which the survey left and
    no view of the object needs) are free for visibility, and only contour voxels inside it count and anchor
    candidates. Safety is unchanged: candidates and paths use the true states' safety grid, where unknown space
    is an obstacle.
    """

    pitch_deg: float = -25.0
    focus: np.ndarray | None = None

    def utility_grid(self) -> tuple[StateGrid, np.ndarray]:
        """The state grid the utility sees, and the contour ids that count."""
        contour = self.derived.contour_ids()
        if self.focus is None:
            return self.grid, contour
        states = self.grid.states.copy()
        states[(states == UNKNOWN) & ~self.focus] = FREE
        return StateGrid(states, self.grid.key_lo, self.grid.resolution), contour[self.focus.reshape(-1)[contour]]

    def mounted(self, views: Views) -> Views:
        return Views(views.positions, views.heading_deg, np.full(len(views), self.pitch_deg))


def object_region(grid: StateGrid, target: Target, seabed: float) -> np.ndarray:
    """Mask of the grid voxels around the object: within `FOCUS_MARGIN_M` of its footprint's circle, from above
    its top down to just under the seabed."""
    ijk = np.indices(grid.shape).reshape(3, -1).T
    c = grid.centres(ijk)
    near = np.hypot(c[:, 0] - target.north, c[:, 1] - target.east) <= target.radius + FOCUS_MARGIN_M
    level = (c[:, 2] >= target.top_depth - FOCUS_MARGIN_M) & (c[:, 2] <= seabed + 0.25)
    return np.asarray((near & level).reshape(grid.shape))


def scan_of(frame: ScanFrame) -> Scan:
    """A scanner frame placed at its estimated pose (flat attitude), as the planner takes it."""
    origin = np.array([frame.north, frame.east, frame.depth])
    dirs = frame.directions_body @ rotation_zyx(frame.heading).T
    return Scan(origin, origin + dirs * frame.ranges[:, None], frame.hit)


def mount_tilt_deg(frame: ScanFrame) -> float:
    """The scanner's downward tilt, from the mean direction of its rays."""
    mean = frame.directions_body.mean(axis=0)
    return math.degrees(math.asin(float(mean[2] / np.linalg.norm(mean))))


@dataclass
class TargetRun:
    """One target's exploration: its planner and what happened."""

    target: Target
    planner: FixedMountNbv
    lo: np.ndarray
    hi: np.ndarray
    seabed: float
    start: View
    views: list[tuple[float, float, float, float, float]] = field(default_factory=list)
    iterations_ms: list[float] = field(default_factory=list)
    integrate_ms: list[float] = field(default_factory=list)
    volume: list[tuple[float, float, float]] = field(default_factory=list)  # time, known m³, coverage estimate
    rejected: int = 0
    replans: int = 0
    stop_reason: str = ""
    estimate: float = 0.0
    focus_done_at: float | None = None
    """When the object's region had nothing left to reveal (then the whole box is explored)."""

    def object_voxels(self) -> np.ndarray:
        """Flat grid ids of the occupied voxels that belong to the object (above the seabed, over its footprint)."""
        grid = self.planner.grid
        ids = grid.occupied_ids
        c = grid.centres(np.stack(np.unravel_index(ids, grid.shape), axis=1))
        t = self.target
        near = np.hypot(c[:, 0] - t.north, c[:, 1] - t.east) <= t.radius + 1.5
        return np.asarray(ids[near & (c[:, 2] < self.seabed - 0.4)])

    def expected_voxels(self) -> float:
        """Surface voxels the detection's box would have: its top and four sides."""
        t, res = self.target, self.planner.grid.resolution
        height = max(self.seabed - t.top_depth, 0.0)
        return (t.length * t.width + 2.0 * (t.length + t.width) * height) / res**2

    def coverage_estimate(self) -> float:
        """The map's own estimate of the object's observed surface: the share of its mapped voxels off the open
        contour (seen with their surroundings), times how many are mapped against what its detected box would
        have (so that a few voxels seen early do not pass for a finished model)."""
        ids = self.object_voxels()
        if not len(ids):
            return 0.0
        open_edge = self.planner.derived.contour.reshape(-1)[ids]
        return float((1.0 - open_edge.mean()) * min(1.0, len(ids) / max(self.expected_voxels(), 1.0)))


class ExploreAgent(Agent):
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
        self.details = {"planner": p.planner, "objects": [], "views": 0}
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
        self.payload = frozenset({"scanner"})
        self.tilt: float | None = None
        self.index = -1
        self.phase = "approach"
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
        lo, hi = exploration_box(target, self.safe, self.model.max_range, ceiling=self.cruise_depth - 1.0)
        products = survey_map_for(self.context.knowledge, target)
        vm = prior_map(products, lo, hi, RESOLUTION_M, uncertain=PRIOR_UNCERTAIN_M)
        seabed = seabed_depth(products, target, target.radius + 1.0)
        planner = FixedMountNbv(vm, lo, hi, self.model, weights=self.weights, safe_distance=self.safe,
                                seed=self.context.mission.seed + self.index)
        planner.focus = object_region(planner.grid, target, seabed)
        planner.min_unknown = MIN_UNKNOWN  # the object's region alone holds few unknown voxels a view can reach
        start = self._start_view(planner, target, seabed, nav)
        if start is None:
            self.context.emit("explore_no_start", nav.time, element=self.context.element.id, object=target.id)
            self.runs.append(TargetRun(target, planner, lo, hi, seabed, View.at(target.centre),
                                       stop_reason="no safe starting view"))
            self.run = self.runs[-1]
            self._next_target(nav)
            return
        self.run = TargetRun(target, planner, lo, hi, seabed, start)
        self.runs.append(self.run)
        self.phase = "approach"
        self.rejections = 0

    def _start_view(self, planner: FixedMountNbv, target: Target, seabed: float, nav: NavState) -> View | None:
        """A safe, known-free view facing the object, on the vehicle's side of it, as near the ideal as found."""
        bearing = math.atan2(nav.east - target.east, nav.north - target.north)
        depth0 = seabed - self.safe - 1.5
        for dr in (2.0, 3.0, 4.0, 5.0):
            for dd in (0.0, -1.0, -2.0, -3.0):
                for da in np.radians([0, 20, -20, 40, -40, 60, -60, 90, -90, 120, -120, 150, -150, 180]):
                    r = target.radius + self.safe + dr
                    p = np.array([target.north + r * math.cos(bearing + da), target.east + r * math.sin(bearing + da),
                                  depth0 + dd])
                    if planner.grid.state(p[None])[0] == FREE and is_safe_view(planner.safety, p[None],
                                                                                 self.safe)[0]:
                        heading = math.degrees(math.atan2(target.east - p[1], target.north - p[0])) % 360.0
                        return View.at(p, heading, -(self.tilt if self.tilt is not None else 25.0))
        return None

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
        budget_left = self.params.budget - (nav.time - self.t0)
        climb = max(0.0, nav.depth - self.exit_depth) / CLIMB_RATE + 15.0
        if self.phase != "leave" and budget_left <= climb:
            if self.run is not None:
                self.run.stop_reason = self.run.stop_reason or "budget"
            self._leave()
        here = np.array([nav.north, nav.east, nav.depth])
        if self.phase == "approach":
            return self._approach(nav, here)
        if self.phase == "move":
            return self._move(nav, here)
        if self.phase == "settle":
            return self._settle(nav, here)
        if self.phase == "propose":
            return self._propose(nav, here)
        return self._climb(nav)

    def _integrate(self, frame: ScanFrame) -> None:
        if self.tilt is None:
            self.tilt = mount_tilt_deg(frame)
            for other in self.runs:
                other.planner.pitch_deg = -self.tilt
        run = self.run
        if run is None or self.phase == "leave":
            return
        # Frames from (nearly) the pose of the last one add little to the planner's map but cost as much: they
        # are skipped, except the first frame at a view. The metric `surface_observed_percent` counts every
        # frame the sensor took (the simulator logs their true hits), fused or not.
        pose = (frame.north, frame.east, frame.depth, frame.heading)
        wanted = self.phase == "settle" and self.aligned_at is not None and self.last_scan <= self.aligned_at
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
        if self.phase == "move" and self.path is not None and len(run.integrate_ms) % 2 == 0 \
                and not self._path_still_safe(self.path):
            run.replans += 1
            self.phase = "propose"

    def _path_still_safe(self, path: StationPath) -> bool:
        assert self.run is not None
        rest = path.remaining()
        safety = self.run.planner.safety
        return all(segment_safe(safety, a, b, self.safe) for a, b in zip(rest[:-1], rest[1:], strict=True))

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
        self.phase = "move"
        self.aligned_at = None

    def _move(self, nav: NavState, here: np.ndarray) -> Command:
        assert self.path is not None and self.goal is not None
        carrot = self.path.carrot(here)
        if self.path.done:
            self.phase = "settle"
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
            self.phase = "propose"
        return self._hold()

    def _propose(self, nav: NavState, here: np.ndarray) -> Command:
        run = self.run
        assert run is not None and self.goal is not None
        run.estimate = run.coverage_estimate()
        if run.estimate >= COVERAGE_TARGET:
            self._next_target(nav, "coverage target")
            return self._hold() if self.phase != "approach" else self._approach(nav, here)
        t0 = time.perf_counter()
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
            return self._hold() if self.phase not in ("approach",) else self._approach(nav, here)
        path = connect(run.planner.safety, here, view.point, self.safe, seed=self.context.mission.seed)
        run.iterations_ms.append(1e3 * (time.perf_counter() - t0))
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
        self.phase = "leave"
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
            self.photo.finish(self.details)
            return
        occupied: list[np.ndarray] = []
        views: list[tuple[float, ...]] = []
        volume: list[tuple[float, ...]] = []
        boxes: list[list[float]] = []
        objects: list[dict[str, object]] = []
        for k, run in enumerate(self.runs):
            grid = run.planner.grid
            ids = grid.occupied_ids
            centres = grid.centres(np.stack(np.unravel_index(ids, grid.shape), axis=1))
            occupied.append(np.column_stack([centres, np.full(len(centres), k)]))
            views.extend((*v, k) for v in run.views)
            volume.extend((*v, k) for v in run.volume)
            boxes.append([*run.lo, *run.hi])
            it = run.iterations_ms
            run.estimate = run.coverage_estimate() if run.stop_reason != "no safe starting view" else 0.0
            objects.append({
                "id": run.target.id, "source": run.target.source, "north": round(run.target.north, 2),
                "east": round(run.target.east, 2), "views": len(run.views),
                "stop_reason": run.stop_reason or "element ended",
                "object_region_done_s": None if run.focus_done_at is None else round(run.focus_done_at - self.t0, 1),
                "coverage_estimate_percent": round(100.0 * run.estimate, 1),
                "rejected_views": run.rejected, "replans": run.replans,
                "iteration_time_ms": {"mean": round(float(np.mean(it)), 1) if it else None,
                                      "max": round(float(np.max(it)), 1) if it else None},
                "scan_integration_ms": round(float(np.mean(run.integrate_ms)), 1) if run.integrate_ms else None,
                "object_voxels_mapped": int(len(run.object_voxels()))})
        all_it = [t for r in self.runs for t in r.iterations_ms]
        self.details.update({
            "objects": objects, "views": sum(len(r.views) for r in self.runs),
            "iteration_time_ms": {"mean": round(float(np.mean(all_it)), 1) if all_it else None,
                                  "max": round(float(np.max(all_it)), 1) if all_it else None},
            "resolution_m": RESOLUTION_M, "safe_distance_m": self.params.safe_distance,
            "planning_distance_m": self.safe,
            "scanner_tilt_deg": round(self.tilt, 2) if self.tilt is not None else None})
        self.context.knowledge.maps[self.context.element.id] = {
            "explore_occupied": np.concatenate(occupied).astype(np.float32) if occupied else np.zeros((0, 4)),
            "explore_views": np.asarray(views, dtype=np.float64).reshape(-1, 6),
            "explore_volume": np.asarray(volume, dtype=np.float64).reshape(-1, 4),
            "explore_track": np.asarray(self.track, dtype=np.float64).reshape(-1, 4),
            "explore_boxes": np.asarray(boxes, dtype=np.float64).reshape(-1, 6),
            "explore_resolution": np.array(RESOLUTION_M)}


__all__ = ["COVERAGE_TARGET", "ExploreAgent", "FixedMountNbv", "NAV_MARGIN_M", "mount_tilt_deg", "scan_of"]
