"""The `inspect` agent (seed 002 §3.4, Figs 11–13): photograph a known object's targets.

The vehicle reaches the object by acoustic navigation and visits point sets and targets in an order that
minimises distance and transitions (`itinerary.Itinerary`; a set before the targets referenced to it). At a set
(`visit.SetVisit`) it searches until the referencing plug-in recognises a set, then references precisely, fusing
several views (`referencer.Referencer`); that fix places the object in the navigation frame and starts an
odometry chain (`odometry.OdometryChain`) that keeps re-anchoring the object, so that the vehicle moves in the
object's frame. Each target is photographed from its viewpoint (`targets.TargetVisit`). When the assumed
odometry drift grows or tracking is lost, the vehicle re-references at the nearest set; when a set is not
recognised, its targets are bound to another set and the order is re-planned from where the vehicle is.

Plug-in calls are asynchronous: results are polled every tick and used with the estimate of their frame's time;
while waiting, the vehicle holds its station or keeps its leg. Everything here runs on the estimate; the
`InspectReport` keeps what metrics need to score it against the truth.
"""

from __future__ import annotations

import math
from collections.abc import Collection

import numpy as np

from mission.agents.base import Agent, AgentContext
from mission.agents.inspect.itinerary import Itinerary
from mission.agents.inspect.motion import Mover
from mission.agents.inspect.odometry import OdometryChain
from mission.agents.inspect.placement import Placement
from mission.agents.inspect.referencer import Referencer
from mission.agents.inspect.settings import InspectSettings
from mission.agents.inspect.states import StopKind
from mission.agents.inspect.surroundings import Surroundings
from mission.agents.inspect.targets import TargetVisit
from mission.agents.inspect.viewing import SetViewer
from mission.agents.inspect.visit import SetVisit
from mission.agents.known_object import database_pose
from mission.agents.report import InspectReport, TargetOutcome
from mission.geometry import invert, transform_points
from mission.language.detectability import rate_object
from mission.language.mount import DOWN_DEG
from mission.vehicle import Command, NavState, Observation


class InspectAgent(Agent):
    """Sequences the stops of an inspection; the parts do the work at each stop."""

    kind = "inspect"

    def __init__(self, settings: InspectSettings | None = None) -> None:
        super().__init__()
        self.settings = settings or InspectSettings()
        self.stop_kind: StopKind | None = None  # None: no stop under way

    def start(self, context: AgentContext) -> None:
        s = self.settings
        p = context.element.inspect
        assert p is not None
        self.context = context
        obj = context.mission.object(p.object)
        stereo = context.mission.sensors.stereo
        # the image's field at unit range (width, height) and how far the cameras see
        field = (stereo.width / stereo.fx, stereo.height / stereo.fx) if stereo is not None else (1.2, 0.9)
        sets = {ps.id: np.asarray(ps.points, dtype=float) for ps in obj.characteristic_points}
        wanted = [t.id for t in obj.targets] if p.targets == "all" else list(p.targets)
        targets = {t.id: t for t in obj.targets if t.id in wanted}
        self.place = Placement(database_pose(obj), stereo.baseline if stereo is not None else 0.0,
                               stereo.mount.tilt_deg if stereo is not None else DOWN_DEG)
        self._survey_prior(context, obj.id, obj.size)
        nav = context.nav
        start = transform_points(invert(self.place.T_wo), np.array([[nav.north, nav.east, nav.depth]]))[0]
        ratings = {r.set_id: r.rating for r in rate_object(obj, stereo)}
        self.itinerary = Itinerary(sets, targets, p.order, start, context.mission.seed, s.set_cost_m, ratings)
        plan = self.itinerary.plan
        self.report = InspectReport(
            obj.id, [list(stop) for stop in self.itinerary.queue], round(plan.length_m, 2), plan.exact,
            {tid: TargetOutcome(t.photos, t.reference) for tid, t in targets.items()})
        self.details = self.report
        self.chain = OdometryChain(context.plugins, self.place, s, report=self.report.vo)
        speed = min(context.mission.vehicle.cruise_speed, s.work_speed_m_s)
        known = [*sets.values(), *(np.asarray([t.at]) for t in obj.targets)]
        self.mover = Mover(self.place, known, context.mission.safety.min_altitude, speed, s)
        surroundings = Surroundings.of(known, context.mission.safety.min_altitude + s.altitude_margin_m,
                                       self.place.tilt_deg, s.max_range_ratio)
        self.target_visit = TargetVisit(context, targets, self.report.targets, self.report.photos, self.place,
                                        self.chain, self.mover, self, surroundings, s)
        if context.plugins is None or not context.plugins.has("referencing"):
            self.fail("no referencing plug-in is loaded")
            return
        viewer = SetViewer(sets, field, stereo.max_range if stereo is not None else math.inf, s)
        referencer = Referencer(context.plugins, obj.id, sets, self.place, self.chain, s)
        self.set_visit = SetVisit(context, obj.id, sets, p.search, self.place, viewer, self.chain, referencer,
                                  self.mover, self, self, self.report.attempts, s)
        missing = [t for t in wanted if t not in targets]
        if missing:
            self.fail(f"object '{obj.id}' has no targets {missing}")
            return
        self._next(nav)

    def _survey_prior(self, context: AgentContext, object_id: str, size: tuple[float, float, float]) -> None:
        """When a survey of this mission detected the object, centre the charted footprint on the detection (the
        survey's position is good to a metre or two, often better than the database's; heading kept)."""
        found = [d for d in context.knowledge.detections if d.database_id == object_id]
        if not found:
            return
        det = found[-1]
        length, width, _ = size
        centre = transform_points(self.place.T_wo, np.array([[length / 2, width / 2, 0.0]]))[0]
        shift = np.array([det.north - centre[0], det.east - centre[1], 0.0])
        self.place.T_wo[:3, 3] += shift
        self.place.trusted = self.place.T_wo.copy()
        context.emit("prior_from_survey", context.nav.time, element=context.element.id, detection=det.id,
                     shift_m=[round(float(x), 3) for x in shift[:2]])

    def planned_path(self) -> list[tuple[float, float]]:
        path = []
        for stop in self.itinerary.queue:
            w = transform_points(self.place.T_wo, self.itinerary.position(stop)[None, :])[0]
            path.append((float(w[0]), float(w[1])))
        return path

    # -- the order of stops --------------------------------------------------------------------------------------
    def _next(self, nav: NavState) -> None:
        """Start the next stop, inserting a re-referencing before a target when odometry is not to be trusted."""
        queue = self.itinerary.queue
        if not queue:
            self.stop_kind = None
            missing = [t for t, outcome in self.report.targets.items() if not outcome.done]
            if missing:
                self.fail(f"targets not photographed: {', '.join(missing)}")
            else:
                self.succeed()
            return
        kind, raw = queue[0]
        ident = str(raw)
        if kind == "target" and self.place.fixed and self.chain.needs_rereference():
            reference = self.itinerary.nearest_usable_set(self.itinerary.position(queue[0]))
            if reference is not None:
                self.chain.stats.rereferences += 1
                self.context.emit("rereference", nav.time, element=self.context.element.id, set=reference,
                                  before=ident, assumed_drift_m=round(self.chain.assumed_drift_m(), 4),
                                  lost_frames=self.chain.lost)
                queue.insert(0, ("set", reference))
                kind, ident = "set", reference
        queue.pop(0)
        if kind == "set":
            self.stop_kind = StopKind.SET
            self.set_visit.begin(ident, ("set", ident) in self.itinerary.done)
        else:
            self.stop_kind = StopKind.TARGET
            self.target_visit.begin(ident, nav.time)

    # what the set visit tells (`visit.SetStops`)
    def failed_sets(self) -> Collection[str]:
        return {str(s) for s in self.itinerary.failed}

    def switched(self, planned: str) -> None:
        self.itinerary.queue.insert(0, ("set", planned))

    def referenced(self, set_id: str, nav: NavState) -> None:
        self.itinerary.done.append(("set", set_id))
        self._next(nav)

    def set_failed(self, set_id: str, nav: NavState) -> None:
        here = self.place.camera_in_object(nav)[:3, 3]
        pending = {t for t, outcome in self.report.targets.items() if not outcome.done}
        record = self.itinerary.replan(set_id, here, pending)
        self.report.replans.append({"time": nav.time, **record})
        self.report.unreachable = list(self.itinerary.plan.unreachable)
        self.report.order = self.report.order + [["replan", set_id]] + [list(s) for s in self.itinerary.queue]
        self.context.emit("inspection_replanned", nav.time, element=self.context.element.id, **record)
        self._next(nav)

    def rereference_failed(self, nav: NavState) -> None:
        self._next(nav)

    def search_failed(self, reason: str, nav: NavState) -> None:
        self.stop_kind = None
        self.fail(reason)

    # what the target visit tells (`targets.TargetStops`)
    def photographed(self, tid: str, nav: NavState) -> None:
        self.itinerary.done.append(("target", tid))
        self._next(nav)

    def odometry_lost(self, tid: str, nav: NavState) -> None:
        self.itinerary.queue.insert(0, ("target", tid))
        self._next(nav)  # re-references first: the chain is broken

    # -- the loop ------------------------------------------------------------------------------------------------
    def step(self, observation: Observation) -> Command:
        nav = observation.nav
        frame = observation.stereo[-1] if observation.stereo else None
        if self.stop_kind is None:
            return Command.hold(nav)
        self.chain.poll(nav.time)
        self.set_visit.poll(nav)  # a result may end the stop, or the inspection
        if self.stop_kind is StopKind.SET:
            return self.set_visit.step(nav, frame)
        if self.stop_kind is StopKind.TARGET:
            return self.target_visit.step(nav, frame)
        return Command.hold(nav)
