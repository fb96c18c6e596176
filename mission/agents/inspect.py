"""The `inspect` agent (seed 002 §3.4, Figs 11–13): photograph a known object's targets.

The vehicle reaches the object by acoustic navigation and visits point sets and targets in an order that
minimises distance and transitions (`planners.ordering`; a set before the targets referenced to it). At a set it
searches (an expanding square or a small meander around the set as placed by its best estimate of the object)
until the referencing plug-in recognises the set, then hovers over the set and references precisely, fusing
several views; that fix places the object in the navigation frame and starts a visual-odometry chain. Between
fixes the camera's pose in the object frame is the fix composed with the odometry plug-in's motion, and the
object is re-anchored in the (dead-reckoned) navigation frame on every odometry frame, so the vehicle moves in
the object's frame. Each target is photographed from its viewpoint — `standoff` metres above it, the camera
looking down at it — with the requested number of photos, saved with their estimated poses. When the assumed
odometry drift grows or tracking is lost, the vehicle re-references at the nearest set; when a set is not
recognised, its targets are bound to another set and the order is re-planned from where the vehicle is.

Everything here runs on the estimate; `details` keeps what metrics need to score it against the truth.
"""

from __future__ import annotations

import math
import time
from collections.abc import Hashable
from typing import Any

import numpy as np

from mission.agents.base import Agent, AgentContext
from mission.agents.fusion import VIEW_AGREEMENT_M, View, fuse_views
from mission.agents.hover import Goal, hover_command
from mission.frames import camera_pose, invert, pose_matrix, transform_points
from mission.language.models import Inspect, KnownObject
from mission.plugin_api import OdometryRequest, OdometryResult, PointSetModel, ReferencingRequest
from mission.vehicle import Command, NavState, Observation
from planners.ordering import Stop

FINE_ALTITUDE_M = 3.6  # above a set's top for the precise referencing (seed 000's experiments), at the least
SEARCH_ALTITUDE_M = 5.0  # above a set's top while searching: a wide view, at the least
VIEW_FILL = 0.75  # a set spans at most this share of the image's width and height in its fine view
FINE_STEPS_M = (0.0, 0.4, 0.8)  # successive fine views cycle through these heights above the fine altitude:
# single-view recognition depends sharply on the range (which corners stand out of the seabed's texture)
RANGE_MARGIN_M = 0.5  # the set's deepest point stays this far inside the stereo range
SEARCH_STEP_M = 1.5  # expanding-square leg unit: well inside the footprint at the search altitude
SEARCH_POSITIONS = 9  # pattern positions around each set
SEARCH_RAISE_M = 0.6  # every other ring of the search this much higher
SETTLE_S = 2.0
FINE_VIEWS = 3  # recognised views fused into one fix
CONFIRM_TRIES = 4  # closer views that may fail to recognise a search hit's set before the hit is dropped
FINE_SHIFT_M = 0.15  # successive fine views move this far along the object's x-axis
SEARCH_PRIOR_RADIUS_M = 4.0  # how far the database pose plus navigation may be off
FINE_PRIOR_RADIUS_M = 0.4  # how far the current estimate may be off once referenced
TOLERANCE_M = 0.05  # pairwise-distance consistency for identification
FRAME_RATE_HZ = 2.0  # stereo frames while moving by odometry
PASSING_RATE_HZ = 0.5  # searching, frames taken on the way between positions are tried too, this often
PASSING_DEPTH_M = 0.5  # ... once the vehicle is within this of the search depth
VO_DRIFT_PER_M = 0.01  # assumed odometry drift per metre travelled since the fix
REREFERENCE_DRIFT_M = 0.04  # re-reference before a target when the assumed drift exceeds this
FIX_GATE_M = 0.15  # once placed, a view that moves the set farther than this (plus 3× the assumed odometry
# drift) from where odometry tracks it is a wrong identification, not a correction
VO_LOST_FRAMES = 4  # consecutive lost frames that end an odometry chain
VO_MAX_STEP_M = 0.5  # a jump larger than this between frames is not motion but a failure
VIEWPOINT_TOLERANCE_M = 0.03
VIEWPOINT_DEPTH_TOLERANCE_M = 0.05  # the depth sensor's noise is 2 cm
PHOTO_INTERVAL_S = 1.0
SET_COST_M = 8.0  # a set's search and referencing, in metres of travel, for the ordering
HOVER_SPEED_M_S = 1.0
CLEARANCE_MARGIN_M = 1.0  # above the minimum altitude when crossing the object
ALTITUDE_MARGIN_M = 0.2  # kept above the mission's minimum altitude, by the altimeter, whatever the plan says
STATION_RADIUS_M = 10.0  # over the object the vehicle hovers from stop to stop (cruising, it would circle)
OVER_GOAL_M = 0.6  # descend to a goal's depth only within this horizontal distance of it


def database_pose(obj: KnownObject) -> np.ndarray:
    """T_world_object as the database has it (z parallel to the world z, per seed 000 §3.1)."""
    return pose_matrix(obj.pose.north, obj.pose.east, obj.pose.depth, obj.pose.heading)


def fit_altitude(points: np.ndarray, field: tuple[float, float], fill: float = VIEW_FILL) -> float:
    """The range from a down-looking camera at which a point set (object frame, z down) fits in `fill` of the
    image, its longer horizontal side along the image's width; `field` is the image's (width, height) at unit
    range. Seed 002's fine views need the whole set: a set cut by the image's edge is not recognised.

    >>> round(fit_altitude(np.array([[0, 0, 0], [5, 0, 0], [5, 1.5, 0]]), (1.2, 0.9)), 3)  # 5 m / (0.75 · 1.2)
    5.556
    """
    extent = np.sort(np.ptp(np.asarray(points, dtype=float)[:, :2], axis=0))[::-1]
    return float(max(extent[0] / (fill * field[0]), extent[1] / (fill * field[1])))


def expanding_square(step: float, count: int) -> list[tuple[float, float]]:
    """North/east offsets of an expanding-square search: legs of 1, 1, 2, 2, 3, … steps turning clockwise.

    >>> expanding_square(1.0, 6)
    [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (2.0, -1.0)]
    """
    out = [(0.0, 0.0)]
    n = e = 0.0
    directions = ((1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0))
    leg = 0
    while len(out) < count:
        dn, de = directions[leg % 4]
        length = leg // 2 + 1
        n, e = n + dn * length * step, e + de * length * step
        out.append((n, e))
        leg += 1
    return out


def meander_offsets(step: float, count: int) -> list[tuple[float, float]]:
    """North/east offsets of a small meander centred on the origin (rows `step` apart, east–west passes).

    >>> meander_offsets(1.0, 5)
    [(0.0, 0.0), (-1.0, -1.0), (-1.0, 0.0), (-1.0, 1.0), (0.0, 1.0)]
    """
    side = max(3, math.ceil(math.sqrt(max(count - 1, 1))) | 1)
    half = side // 2
    out = [(0.0, 0.0)]
    for i, row in enumerate(range(-half, half + 1)):
        cols = range(-half, half + 1) if i % 2 == 0 else range(half, -half - 1, -1)
        out.extend((row * step, col * step) for col in cols if (row, col) != (0, 0))
    return out[:count]


class InspectAgent(Agent):
    kind = "inspect"

    # -- set-up ------------------------------------------------------------------------------------------------
    def start(self, context: AgentContext) -> None:
        from planners.ordering import inspection_order

        p = context.element.inspect
        assert p is not None
        self.params: Inspect = p
        self.context = context
        self.obj = context.mission.object(p.object)
        stereo = context.mission.sensors.stereo
        self.baseline = stereo.baseline if stereo is not None else 0.0
        # the image's field at unit range (width, height) and how far the cameras see
        self.field = (stereo.width / stereo.fx, stereo.height / stereo.fx) if stereo is not None else (1.2, 0.9)
        self.max_range = stereo.max_range if stereo is not None else math.inf
        self.sets = {s.id: np.asarray(s.points, dtype=float) for s in self.obj.characteristic_points}
        wanted = [t.id for t in self.obj.targets] if p.targets == "all" else list(p.targets)
        self.targets = {t.id: t for t in self.obj.targets if t.id in wanted}
        self.T_wo = database_pose(self.obj)  # T_world_object in the navigation frame: database, then fixes
        self._survey_prior(context)
        self.T_wo_trusted = self.T_wo.copy()  # the database pose or the last fused fix
        self.search_started: float | None = None
        self.search_goals: list[Goal] = []
        self.unconfirmed: set[str] = set()  # sets whose search hit the closer views did not confirm
        self.search_index = 0
        self.fixed = False
        self.speed = min(context.mission.vehicle.cruise_speed, HOVER_SPEED_M_S)
        start = transform_points(invert(self.T_wo), np.array([[context.nav.north, context.nav.east,
                                                               context.nav.depth]]))[0]
        set_pos: dict[Hashable, Any] = {s: pts.mean(axis=0) for s, pts in self.sets.items()}
        spec: dict[Hashable, Any] = {tid: (np.asarray(t.at, dtype=float), self._candidates(t.reference, t.at))
                                     for tid, t in self.targets.items()}
        binding: dict[Hashable, Hashable] = {tid: t.reference for tid, t in self.targets.items()}
        self.plan = inspection_order(start, set_pos, spec, seed=context.mission.seed, binding=binding,
                                     set_cost=SET_COST_M)
        if p.order == "as-listed":
            self.queue = self._as_listed(binding)
        else:
            self.queue = list(self.plan.order)
        self.done: list[Stop] = []
        self.attempts: list[dict[str, Any]] = []
        self.photos: list[dict[str, Any]] = []
        self.replans: list[dict[str, Any]] = []
        self.vo_track: list[list[float]] = []
        self.vo_stats = {"frames": 0, "lost": 0, "chains": 0, "rereferences": 0}
        self.details = {
            "object": self.obj.id, "order": [list(s) for s in self.queue],
            "plan_length_m": round(self.plan.length_m, 2),
            "exact_order": self.plan.exact, "attempts": self.attempts, "photos": self.photos,
            "replans": self.replans, "vo": {"track": self.vo_track, **self.vo_stats},
            "targets": {tid: {"photos_requested": t.photos, "photos": 0, "viewpoint_object": None,
                              "reference": t.reference} for tid, t in self.targets.items()},
            "unreachable": []}
        self.odometry = context.plugins is not None and context.plugins.has("odometry")
        self.T_object_origin: np.ndarray | None = None  # camera pose in the object frame at the chain's origin
        self.vo_path = 0.0
        self.path_since_fix = 0.0  # odometry path since the last fused fix: what the fix gate allows for
        self.vo_lost = 0
        self.last_c: np.ndarray | None = None
        self.navigation = "usbl"
        self.task: tuple[str, Any] | None = None
        if context.plugins is None or not context.plugins.has("referencing"):
            self.fail("no referencing plug-in is loaded")
            return
        missing = [t for t in wanted if t not in self.targets]
        if missing:
            self.fail(f"object '{self.obj.id}' has no targets {missing}")
            return
        self._next(context.nav)

    def _survey_prior(self, context: AgentContext) -> None:
        """When a survey of this mission detected the object, centre the charted footprint on the detection (the
        survey's position is good to a metre or two, often better than the database's; heading kept)."""
        found = [d for d in context.knowledge.detections if d.database_id == self.obj.id]
        if not found:
            return
        det = found[-1]
        length, width, _ = self.obj.size
        centre = transform_points(self.T_wo, np.array([[length / 2, width / 2, 0.0]]))[0]
        shift = np.array([det.north - centre[0], det.east - centre[1], 0.0])
        self.T_wo[:3, 3] += shift
        context.emit("prior_from_survey", context.nav.time, element=context.element.id, detection=det.id,
                     shift_m=[round(float(x), 3) for x in shift[:2]])

    def _candidates(self, reference: str, at: Any) -> list[str]:
        """The target's own set first, then the others by distance (for re-binding when a set fails)."""
        others = sorted((s for s in self.sets if s != reference),
                        key=lambda s: float(np.linalg.norm(self.sets[s].mean(axis=0) - np.asarray(at))))
        return [reference, *others]

    def _as_listed(self, binding: dict[Hashable, Hashable]) -> list[Stop]:
        order: list[Stop] = []
        for tid in self.targets:
            if ("set", binding[tid]) not in order:
                order.append(("set", binding[tid]))
            order.append(("target", tid))
        return order

    def planned_path(self) -> list[tuple[float, float]]:
        T = self.T_wo
        path = []
        for kind, raw in self.queue:
            ident = str(raw)
            p = self.sets[ident].mean(axis=0) if kind == "set" else np.array(self.targets[ident].at, dtype=np.float64)
            w = transform_points(T, p[None, :])[0]
            path.append((float(w[0]), float(w[1])))
        return path

    # -- geometry on the estimate -------------------------------------------------------------------------------
    def _object_heading(self) -> float:
        x_axis = self.T_wo[:3, 0]
        return math.degrees(math.atan2(x_axis[1], x_axis[0])) % 360.0

    def _camera_goal(self, camera_world: np.ndarray, heading: float) -> Goal:
        """The hover pose that puts the left camera at `camera_world` with the vehicle at `heading`."""
        offset = camera_pose(0.0, 0.0, 0.0, heading, baseline=self.baseline)[:3, 3]
        body = camera_world - offset
        return Goal(float(body[0]), float(body[1]), float(body[2]), heading)

    def _over_set(self, set_id: str, altitude: float, shift: tuple[float, float] = (0.0, 0.0),
                  along_set: bool = False) -> Goal:
        """Hover over a set's centroid (as currently placed) at `altitude` above its top, aligned with the object
        (seed 002 §3.3): the image's long side (camera x) along the object's x-axis, or with `along_set` along the
        object's axis on which the set is longer (searching, so that the whole set fits)."""
        pts = transform_points(self.T_wo, self.sets[set_id])
        centre = pts.mean(axis=0)
        camera = np.array([centre[0] + shift[0], centre[1] + shift[1], float(pts[:, 2].min()) - altitude])
        extent = np.ptp(self.sets[set_id][:, :2], axis=0)
        along_x = extent[0] >= extent[1] or not along_set
        return self._camera_goal(camera, (self._object_heading() - (90.0 if along_x else 0.0)) % 360.0)

    def _fit_altitude(self, set_id: str) -> float:
        """How high above a set's top the whole set is in view (`fit_altitude`), no lower than
        `FINE_ALTITUDE_M`, and its deepest point inside the stereo range."""
        return min(max(FINE_ALTITUDE_M, fit_altitude(self.sets[set_id], self.field)), self._range_ceiling(set_id))

    def _fine_altitude(self, set_id: str) -> float:
        """Fine views are taken at the seed's 3.6 m above the set, where stereo is precise enough for the
        photographs' 0.1 m (measured: higher views are recognised more often but fix the object a few
        centimetres and about a degree worse, and a skid set's wrong matches then agree with one another)."""
        return min(FINE_ALTITUDE_M, self._range_ceiling(set_id))

    def _agreement(self) -> float:
        """How closely views of the current set must agree: `VIEW_AGREEMENT_M` at the seed's 3.6 m, growing
        with the range like the stereo depth error (σ_Z ∝ Z²), as the plug-in's own tolerance does."""
        pts = self.sets[self.set_id]
        reach = self._fine_altitude(self.set_id) + FINE_STEPS_M[len(FINE_STEPS_M) // 2] + float(np.ptp(pts[:, 2]))
        return VIEW_AGREEMENT_M * max(1.0, (reach / FINE_ALTITUDE_M) ** 2)

    def _range_ceiling(self, set_id: str) -> float:
        """The highest view above a set's top that keeps its deepest point inside the stereo range."""
        return self.max_range - float(np.ptp(self.sets[set_id][:, 2])) - RANGE_MARGIN_M

    def _search_altitude(self, set_id: str) -> float:
        """Searching, a little above the fine view: a wider field for the larger position uncertainty."""
        return float(min(max(SEARCH_ALTITUDE_M, self._fit_altitude(set_id) + SEARCH_RAISE_M),
                         self._range_ceiling(set_id) - SEARCH_RAISE_M))

    def _clearance_depth(self) -> float:
        """Moving across the object, stay this shallow: its highest known point plus the minimum altitude and a
        margin."""
        points = np.vstack([*self.sets.values(), *(np.asarray([t.at]) for t in self.obj.targets)])
        top = float(transform_points(self.T_wo, points)[:, 2].min())
        return top - self.context.mission.safety.min_altitude - CLEARANCE_MARGIN_M

    def _go(self, nav: NavState, goal: Goal, tolerance: float = 0.3,
            depth_tolerance: float = 0.3) -> tuple[Command, bool]:
        """Hover to `goal` without sweeping low over the object: climb in place to the clearance depth, cross
        at it, and descend only over the goal."""
        floor = self._altitude_floor(nav)
        if floor < goal.depth:  # whatever lies under the vehicle is higher than the plan assumed: keep clear
            goal = Goal(goal.north, goal.east, floor, goal.heading)
        if math.hypot(goal.north - nav.north, goal.east - nav.east) > OVER_GOAL_M:
            depth = min(goal.depth, self._clearance_depth())
            if nav.depth > depth + 0.3:
                return Command(nav.heading, 0.0, depth=depth, station=(nav.north, nav.east)), False
            return hover_command(nav, Goal(goal.north, goal.east, depth, goal.heading), self.speed,
                                 station_m=STATION_RADIUS_M)[0], False
        return hover_command(nav, goal, self.speed, tolerance, depth_tolerance, STATION_RADIUS_M)

    def _altitude_floor(self, nav: NavState) -> float:
        """The deepest the vehicle may go here by its altimeter: the minimum altitude plus a margin."""
        if nav.altitude is None:
            return math.inf
        return nav.depth + nav.altitude - self.context.mission.safety.min_altitude - ALTITUDE_MARGIN_M

    def _camera_in_object(self, nav: NavState) -> np.ndarray:
        T_world_cam = camera_pose(nav.north, nav.east, nav.depth, nav.heading, baseline=self.baseline)
        return invert(self.T_wo) @ T_world_cam

    # -- the order of stops ------------------------------------------------------------------------------------
    def _next(self, nav: NavState) -> None:
        """Start the next stop, inserting a re-referencing before a target when odometry is not to be trusted."""
        while self.queue:
            kind, raw = self.queue[0]
            ident = str(raw)
            if kind == "target" and self.fixed and self._needs_rereference():
                reference = self._nearest_usable_set(np.asarray(self.targets[ident].at, dtype=float))
                if reference is not None:
                    self.vo_stats["rereferences"] += 1
                    self.context.emit("rereference", nav.time, element=self.context.element.id, set=reference,
                                      before=ident, assumed_drift_m=round(VO_DRIFT_PER_M * self.vo_path, 4),
                                      lost_frames=self.vo_lost)
                    self.queue.insert(0, ("set", reference))
                    kind, ident = "set", reference
            self.queue.pop(0)
            self.task = (kind, ident)
            if kind == "set":
                self._begin_set(ident, nav)
            else:
                self._begin_target(ident, nav)
            return
        self.task = None
        missing = [t for t, d in self.details["targets"].items() if d["photos"] < d["photos_requested"]]
        if missing:
            self.fail(f"targets not photographed: {', '.join(missing)}")
        else:
            self.succeed()

    def _needs_rereference(self) -> bool:
        if not self.odometry:
            return False
        return self.T_object_origin is None or self.vo_lost >= VO_LOST_FRAMES or \
            VO_DRIFT_PER_M * self.vo_path > REREFERENCE_DRIFT_M

    def _nearest_usable_set(self, point: np.ndarray) -> str | None:
        usable = [s for s in self.sets if s not in self.plan.failed]
        if not usable:
            return None
        return min(usable, key=lambda s: float(np.linalg.norm(self.sets[s].mean(axis=0) - point)))

    def _replan(self, failed: str, nav: NavState) -> None:
        from planners.ordering import replan

        here = self._camera_in_object(nav)[:3, 3]
        pending_targets = {("target", t) for t, d in self.details["targets"].items()
                           if d["photos"] < d["photos_requested"]}
        done: list[Stop] = [s for s in self.done if s[0] == "set"]
        done += [("target", t) for t in self.targets if ("target", t) not in pending_targets]
        self.plan = replan(self.plan, done, failed, here, seed=self.context.mission.seed)
        self.queue = list(self.plan.order)
        record = {"time": nav.time, "failed_set": failed, "order": [list(s) for s in self.queue],
                  "binding": dict(self.plan.binding), "unreachable": list(self.plan.unreachable)}
        self.replans.append(record)
        self.details["unreachable"] = list(self.plan.unreachable)
        self.details["order"] = self.details["order"] + [["replan", failed]] + [list(s) for s in self.queue]
        self.context.emit("inspection_replanned", nav.time, element=self.context.element.id,
                          **{k: v for k, v in record.items() if k != "time"})

    # -- point sets: search and referencing ----------------------------------------------------------------------
    def _begin_set(self, set_id: str, nav: NavState) -> None:
        self.set_id = set_id
        self.views: list[View] = []
        self.fine_tries = 0
        if self.fixed:  # a good estimate already: straight to the precise referencing
            self._begin_fine(set_id)
            return
        # Until the object is first referenced, the vehicle searches for any of its sets: over each set as the
        # database places it (this one first), then the search pattern around it; one budget for the search.
        self.stage = "search"
        if not self.search_goals:
            self._plan_search()
        self.goals, self.goal_index = self.search_goals, self.search_index
        self.phase = "go"

    def _plan_search(self) -> None:
        offsets = expanding_square(SEARCH_STEP_M, SEARCH_POSITIONS) \
            if self.params.search.pattern == "expanding-square" else meander_offsets(SEARCH_STEP_M,
                                                                                      SEARCH_POSITIONS)
        # Any set will do: the whole pattern around the most distinctive set first (more points, more relief),
        # then around the next, every other position a little higher (recognition is sensitive to the range,
        # and the database may be off in depth too). Flying one set's pattern leg by leg, the frames taken on
        # the way sweep the ground between its positions; alternating sets position by position, they did not
        # (measured: with the database 2.3 m off, no view of 131 had the whole module top in it).
        order = sorted(self.sets, key=lambda s: (-len(self.sets[s]), -float(np.ptp(self.sets[s][:, 2])), s))
        self.search_goals[:] = [self._over_set(s, self._search_altitude(s) + SEARCH_RAISE_M * (ring % 2), o, True)
                                for s in order for ring, o in enumerate(offsets)]

    def _begin_fine(self, set_id: str) -> None:
        self.set_id, self.stage = set_id, "fine"
        self.views, self.fine_tries = [], 0
        self.goals, self.goal_index, self.phase = [self._fine_goal()], 0, "go"

    def _fine_goal(self) -> Goal:
        """The next fine view over the current set: its height cycles through `FINE_STEPS_M`, and it moves
        `FINE_SHIFT_M` back and forth along the object's x-axis (fresh image noise and corners each time)."""
        k = len(self.views) + self.fine_tries
        shift = FINE_SHIFT_M * (1 if k % 2 else -1) if k else 0.0
        x_axis = self.T_wo[:3, 0]
        altitude = min(self._fine_altitude(self.set_id) + FINE_STEPS_M[k % len(FINE_STEPS_M)],
                       self._range_ceiling(self.set_id))
        return self._over_set(self.set_id, altitude, (shift * float(x_axis[0]), shift * float(x_axis[1])))

    def _set_failed(self, nav: NavState, reason: str) -> None:
        if not self.fixed:  # what an unconfirmed search result suggested is dropped (a placed object is tracked)
            self.T_wo = self.T_wo_trusted.copy()
        self.context.emit("set_not_recognised", nav.time, element=self.context.element.id, set=self.set_id,
                          reason=reason, attempts=sum(1 for a in self.attempts if a["set"] == self.set_id))
        self._replan(self.set_id, nav)
        self._next(nav)

    def _reference(self, frame: Any, nav: NavState, passing: bool = False) -> None:
        """One referencing attempt on this frame at the current set (`passing`: a search frame taken on the way
        to the next position; when it shows nothing the vehicle just goes on)."""
        assert self.context.plugins is not None
        T_world_cam = camera_pose(nav.north, nav.east, nav.depth, nav.heading, baseline=self.baseline)
        prior = invert(T_world_cam) @ self.T_wo
        radius = SEARCH_PRIOR_RADIUS_M if self.stage == "search" else FINE_PRIOR_RADIUS_M
        # Searching, any set that is in view will do (the more sets, the surer the identification); once the
        # object is placed, the set the plan visits.
        ids = [s for s in self.sets if s not in self.plan.failed and s not in self.unconfirmed] \
            if self.stage == "search" else [self.set_id]
        ids = ids or [s for s in self.sets if s not in self.plan.failed] or list(self.sets)
        models = tuple(PointSetModel(self.obj.id, s, self.sets[s]) for s in ids)
        t0 = time.perf_counter()
        result = self.context.plugins.process("referencing", frame, ReferencingRequest(
            models, prior, TOLERANCE_M, radius), nav.time)
        record: dict[str, Any] = {
            "time": frame.time, "stage": self.stage, "set": self.set_id, "recognised_set": result.set_id,
            "recognised": bool(result.recognised),
            "matched": int(result.matched), "residual_m": float(result.residual_rms),
            "ambiguous": bool(result.ambiguous), "cloud_points": int(result.cloud_points),
            "time_ms": round(1e3 * (time.perf_counter() - t0), 1)}
        if result.details.get("reason"):
            record["reason"] = result.details["reason"]
        # An ambiguous identification (the prior cannot choose between symmetric matches) is no fix.
        recognised = bool(result.recognised and result.T_cam_object is not None and not result.ambiguous)
        if recognised and self.stage == "fine" and self.fixed and self.odometry and self.vo_lost < VO_LOST_FRAMES:
            assert result.T_cam_object is not None
            points = self.sets[self.set_id]
            jump = float(np.max(np.linalg.norm(transform_points(T_world_cam @ result.T_cam_object, points)
                                               - transform_points(self.T_wo, points), axis=1)))
            gate = FIX_GATE_M + 3.0 * VO_DRIFT_PER_M * self.path_since_fix
            if jump > gate:
                recognised = False
                record["recognised"], record["gated"] = False, True
                record["reason"] = f"{jump:.2f} m from where odometry tracks the set (gate {gate:.2f} m)"
        if recognised:
            T_world_object = T_world_cam @ result.T_cam_object
            record["T_object_cam"] = invert(T_world_object) @ T_world_cam
        self.attempts.append(record)
        self.context.emit("referencing_attempt", nav.time, element=self.context.element.id,
                          **{k: v for k, v in record.items() if not k.startswith("T_") and k != "time"})
        if not recognised:
            if not passing:
                self._not_recognised(frame, nav)
            return
        if not self.fixed:  # placing the object: each view refines the coarse prior the next one is taken with
            self.T_wo = T_world_cam @ result.T_cam_object
        # Re-referencing a placed object, odometry keeps tracking it: the views count only once they agree
        # (a single wrong view must move neither the object nor the odometry chain's origin).
        if self.stage == "search":
            if result.set_id is not None and result.set_id != self.set_id:
                # Referenced through the set that is in view; the planned one keeps its turn, now with a prior.
                self.context.emit("set_switched", nav.time, element=self.context.element.id, planned=self.set_id,
                                  recognised=result.set_id)
                self.queue.insert(0, ("set", self.set_id))
                self.set_id = str(result.set_id)
            self.search_index = self.goal_index
            self._begin_fine(self.set_id)
            return
        if result.model_points is not None and result.points_cam is not None:
            # A placed object's views are kept in its frame as odometry tracks it, not in the navigation frame:
            # dead reckoning drifts centimetres over the minute the views take, and views that agree in the
            # object's frame stopped agreeing in the navigation frame (measured: 6 good views, none fused).
            frame_T = invert(self.T_wo) @ T_world_cam if self.fixed else T_world_cam
            self.views.append((result.model_points, transform_points(frame_T, result.points_cam)))
        fused = fuse_views(self.views, agreement=self._agreement()) if len(self.views) >= 2 else None
        if fused is not None and self.fixed:  # the fusion corrects the tracked frame: compose it
            fused = (self.T_wo @ fused[0], *fused[1:])
        agreeing = fused[1] if fused is not None else 0
        if fused is not None:
            T_fused, n_views, residual, n_points = fused
            self.attempts.append({**{k: v for k, v in record.items() if not k.startswith("T_")},
                                  "stage": "fused", "views": n_views, "matched": n_points, "residual_m": residual,
                                  "T_object_cam": invert(T_fused) @ T_world_cam})
            if not self.fixed or agreeing >= FINE_VIEWS:
                self.T_wo = T_fused
        if not self.fixed or agreeing >= FINE_VIEWS:
            self._start_chain(frame, nav)
        if agreeing < FINE_VIEWS and len(self.views) >= 2 * FINE_VIEWS:
            if self.fixed and ("set", self.set_id) in self.done:
                self._rereference_failed(nav)
            elif self.fixed:
                self._set_failed(nav, f"{len(self.views)} views of the set do not agree")
            else:
                self.T_wo = self.T_wo_trusted.copy()
                self._resume_search(nav)
            return
        if fused is not None and agreeing >= FINE_VIEWS:  # two agreeing views can both be wrong the same way
            self._referenced(nav, fused)
            return
        self.goals, self.goal_index, self.phase = [self._fine_goal()], 0, "go"

    def _referenced(self, nav: NavState, fused: tuple[np.ndarray, int, float, int]) -> None:
        """The fused views fix the object: trust it, count the set as visited and go on."""
        self.T_wo = fused[0]
        self.fixed = True
        self.path_since_fix = 0.0
        self.T_wo_trusted = self.T_wo.copy()
        self.done.append(("set", self.set_id))
        self.context.emit("referenced", nav.time, element=self.context.element.id, set=self.set_id,
                          views=fused[1], points=fused[3], residual_m=round(fused[2], 4))
        self._next(nav)

    def _not_recognised(self, frame: Any, nav: NavState) -> None:
        if self.T_object_origin is not None:
            self._odometry(frame, nav)  # the frame still carries the odometry chain
        if self.stage == "fine":
            self.fine_tries += 1
            # a hit that a closer view has confirmed keeps the longer budget of a placed object
            if self.fine_tries <= (3 * FINE_VIEWS if self.fixed or self.views else CONFIRM_TRIES):
                self.goals, self.goal_index, self.phase = [self._fine_goal()], 0, "go"
            elif self.fixed and ("set", self.set_id) in self.done:
                self._rereference_failed(nav)
            elif self.fixed:
                self._set_failed(nav, "not recognised from above the set")
            else:  # the search's hit was not confirmed: drop it, and trust no more search hits on this set
                self.T_wo = self.T_wo_trusted.copy()
                self.unconfirmed.add(self.set_id)
                self.context.emit("search_hit_dropped", nav.time, element=self.context.element.id, set=self.set_id)
                self._resume_search(nav)
            return
        self.goal_index += 1
        self.search_index = self.goal_index
        self.phase = "go"
        if self.goal_index >= len(self.goals):
            self._search_failed(nav, f"no set of '{self.obj.id}' recognised at {len(self.goals)} search positions")

    def _rereference_failed(self, nav: NavState) -> None:
        """A set referenced here before was not recognised again, or its views did not agree: the set is still
        good and the object still tracked. Go on by odometry (its chain continues) rather than give the set up."""
        self.context.emit("rereference_failed", nav.time, element=self.context.element.id, set=self.set_id,
                          odometry_path_m=round(self.vo_path, 3))
        self.vo_path, self.vo_lost = 0.0, 0  # the next attempt is due after as much motion again
        self._next(nav)

    def _resume_search(self, nav: NavState) -> None:
        self.stage, self.goals, self.views, self.fine_tries = "search", self.search_goals, [], 0
        self.search_index += 1
        self.goal_index, self.phase = self.search_index, "go"
        if self.search_index >= len(self.search_goals):
            self._search_failed(nav, f"no set of '{self.obj.id}' recognised at {len(self.goals)} search positions")

    def _search_failed(self, nav: NavState, reason: str) -> None:
        self.context.emit("object_not_found", nav.time, element=self.context.element.id, reason=reason)
        self.task = None
        self.fail(reason)

    # -- odometry ------------------------------------------------------------------------------------------------
    def _start_chain(self, frame: Any, nav: NavState) -> None:
        """This frame is referenced: it becomes the origin of a new odometry chain."""
        self.T_object_origin = self._camera_in_object(nav)
        self.vo_path, self.vo_lost = 0.0, 0
        self.last_c = self.T_object_origin[:3, 3].copy()
        if self.odometry:
            assert self.context.plugins is not None
            self.context.plugins.process("odometry", frame, OdometryRequest(
                set_origin=True, altitude=nav.altitude, speed=nav.speed), nav.time)
            self.vo_stats["chains"] += 1
        self.frame_rate_hz = FRAME_RATE_HZ
        self.payload = frozenset({"stereo"})
        self.navigation = "dead-reckoning"

    def _odometry(self, frame: Any, nav: NavState) -> None:
        """Move the object in the navigation frame so that the camera sits where odometry says it is."""
        if not self.odometry or self.T_object_origin is None:
            return
        assert self.context.plugins is not None
        result: OdometryResult = self.context.plugins.process("odometry", frame, OdometryRequest(
            altitude=nav.altitude, speed=nav.speed), nav.time)
        self.vo_stats["frames"] += 1
        if not result.ok or result.T_origin_cam is None:
            self.vo_lost += 1
            self.vo_stats["lost"] += 1
            return
        T_object_cam = self.T_object_origin @ result.T_origin_cam
        c = T_object_cam[:3, 3]
        step = float(np.linalg.norm(c - self.last_c)) if self.last_c is not None else 0.0
        if step > VO_MAX_STEP_M:
            self.vo_lost += 1
            self.vo_stats["lost"] += 1
            return
        self.vo_lost = 0
        self.vo_path += step
        self.path_since_fix += step
        self.last_c = c.copy()
        T_world_cam = camera_pose(nav.north, nav.east, nav.depth, nav.heading, baseline=self.baseline)
        self.T_wo[:3, 3] = T_world_cam[:3, 3] - self.T_wo[:3, :3] @ c
        self.vo_track.append([round(frame.time, 3), *(round(float(x), 4) for x in c)])
        self.details["vo"].update(self.vo_stats)

    # -- targets: viewpoint and photographs ------------------------------------------------------------------------
    def _begin_target(self, tid: str, nav: NavState) -> None:
        target = self.targets[tid]
        up = self.T_wo[:3, :3].T @ np.array([0.0, 0.0, -1.0])  # the world's up, in the object frame
        self.target_id = tid
        self.viewpoint = np.asarray(target.at, dtype=float) + target.standoff * up
        self.details["targets"][tid]["viewpoint_object"] = [round(float(x), 4) for x in self.viewpoint]
        self.target_heading = (self._object_heading() - 90.0) % 360.0
        self.phase = "go"
        self.last_photo = -math.inf
        self.target_started = nav.time
        # Whether the altimeter forbade the viewpoint's depth on the way (something under it stands higher than
        # the database says: a tarpaulin over a valve panel); the photos then come from the lowest safe depth,
        # and say so.
        self.altitude_limited = False

    def _target_goal(self) -> Goal:
        camera = transform_points(self.T_wo, self.viewpoint[None, :])[0]
        return self._camera_goal(camera, self.target_heading)

    def _photo(self, frame: Any, nav: NavState) -> None:
        tid = self.target_id
        entry = self.details["targets"][tid]
        k = entry["photos"]
        name = f"photos/{self.context.element.id}/{tid}_{k:02d}.png"
        self.context.artifacts.save_image(name, frame.left)
        T_object_cam = self._camera_in_object(nav)
        limited = self.altitude_limited
        record = {"target": tid, "index": k, "time": frame.time, "file": name,
                  "viewpoint_object": entry["viewpoint_object"],
                  "T_object_cam_est": T_object_cam.round(6).tolist(),
                  "camera_error_est_m": round(float(np.linalg.norm(T_object_cam[:3, 3] - self.viewpoint)), 4),
                  "altitude_limited": limited, "odometry_path_m": round(self.vo_path, 3)}
        self.photos.append(record)
        self.context.artifacts.append_record(f"photos/{self.context.element.id}/index.jsonl", record)
        self.context.emit("photo", nav.time, element=self.context.element.id, target=tid, index=k, file=name,
                          camera_error_est_m=record["camera_error_est_m"], altitude_limited=limited)
        entry["photos"] = k + 1
        self.last_photo = nav.time
        if entry["photos"] >= entry["photos_requested"]:
            self.done.append(("target", tid))
            self._next(nav)

    # -- the loop ------------------------------------------------------------------------------------------------
    def step(self, observation: Observation) -> Command:
        nav = observation.nav
        frame = observation.stereo[-1] if observation.stereo else None
        if self.task is None:
            return Command.hold(nav)
        if self.task[0] == "set":
            return self._step_set(nav, frame)
        return self._step_target(nav, frame)

    def _step_set(self, nav: NavState, frame: Any) -> Command:
        if not self.fixed and self.search_started is not None and \
                nav.time - self.search_started > self.params.search.budget:
            self._search_failed(nav, f"no set of '{self.obj.id}' recognised within the search budget "
                                     f"({self.params.search.budget:.0f} s)")
            return Command.hold(nav)
        goal = self.goals[self.goal_index]
        if self.phase == "capture" and frame is not None:
            self._reference(frame, nav)
            return Command(goal.heading, 0.0, depth=goal.depth, station=(goal.north, goal.east))
        if frame is not None and self.stage == "search" and self.phase == "go":
            # Searching, every frame on the way at about the search depth is a chance (seed 002 §3.4: the
            # search motions go on until a set is recognised).
            if self.search_started is not None and abs(nav.depth - goal.depth) <= PASSING_DEPTH_M:
                self._reference(frame, nav, passing=True)
                if self.stage != "search":  # a hit: the fine views start from here
                    return Command.hold(nav)
        elif frame is not None:
            self._odometry(frame, nav)
        command, there = self._go(nav, goal)
        if self.phase == "go" and there:
            self.phase, self.hold_since = "settle", nav.time
            if self.stage == "search" and self.search_started is None:
                self.search_started = nav.time  # the budget counts from the first search position
                self.navigation = "dead-reckoning"  # near the object, relative navigation is steadier
        elif self.phase == "settle" and nav.time - self.hold_since >= SETTLE_S:
            self.phase = "capture"
            self.payload = frozenset({"stereo"})
        if self.phase == "go" and self.stage == "search" and self.search_started is not None:
            self.payload, self.frame_rate_hz = frozenset({"stereo"}), PASSING_RATE_HZ
        elif self.phase == "go" and self.T_object_origin is None:
            self.payload = frozenset()  # no chain to feed: frames only when capturing
        return command

    def _step_target(self, nav: NavState, frame: Any) -> Command:
        if frame is not None:
            self._odometry(frame, nav)
            if self.odometry and self.vo_lost >= VO_LOST_FRAMES:
                self.context.emit("odometry_lost", nav.time, element=self.context.element.id,
                                  target=self.target_id, lost_frames=self.vo_lost)
                self.queue.insert(0, ("target", self.target_id))
                self._next(nav)  # re-references first: the chain is broken
                return Command.hold(nav)
        goal = self._target_goal()
        over = math.hypot(goal.north - nav.north, goal.east - nav.east) <= OVER_GOAL_M
        if over and self._altitude_floor(nav) < goal.depth - 0.01:
            self.altitude_limited = True
        slack = 1.0 if self.phase == "go" else 2.0  # hysteresis: once there, noise must not send it back
        command, there = self._go(nav, goal, slack * VIEWPOINT_TOLERANCE_M, slack * VIEWPOINT_DEPTH_TOLERANCE_M)
        if self.phase == "go" and there:
            self.phase, self.hold_since = "settle", nav.time
        elif self.phase == "settle":
            if not there:
                self.phase = "go"
            elif nav.time - self.hold_since >= SETTLE_S:
                self.phase = "photo"
        elif self.phase == "photo" and frame is not None and there and \
                nav.time - self.last_photo >= PHOTO_INTERVAL_S - 1e-6:
            self._photo(frame, nav)
        return command
