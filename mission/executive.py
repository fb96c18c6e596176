"""The strategic level (seed 002 §1): run the route elements in order, one tactical agent each, under the
safety monitors; log every event as it happens; on a violation, abort per the mission's `on_violation`.

The executive sees only the vehicle interface (the estimate), never the simulator or plotting. It runs on the
vehicle's clock: `VehicleInterface.advance` lets one control period pass, simulated or real. Onboard it also
- pauses the mission while a pilot has taken the vehicle over (`Observation.in_control` false): agents are not
  stepped, element timers stop, and the mission goes on where it was when the pilot hands the vehicle back;
- ends the run when the vehicle's link is lost (`LinkLostError`): it logs `link_lost` with the mission's
  `on_violation` policy (which it can no longer carry out: the autopilot's own failsafe takes over);
- stops cleanly when asked (`request_stop`, from SIGINT/SIGTERM): the vehicle is told to hold, then to surface if
  the mission's `on_violation` says so.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from mission.agents import REGISTRY, Agent, AgentContext, AgentReport, Status
from mission.agents.transit import TransitAgent
from mission.artifacts import Artifacts
from mission.errors import LinkLostError
from mission.knowledge import Knowledge
from mission.language.models import Mission, RouteElement, Transit
from mission.language.mount import R_body_cam_of
from mission.plugin_host import PluginHost
from mission.safety import SafetyMonitors, Violation, abort_legs, policy_record
from mission.stereo_recording import RECORDING_ACTIONS, ElementStereo
from mission.strategy import StrategicLevel
from mission.vehicle import Command, NavState, Observation, VehicleInterface

MARGIN_S = 120.0  # extra time every default timeout allows


class ElementStatus(enum.StrEnum):
    """How a route element ended (a `str`, so that it compares and serialises as its value)."""

    RUNNING = "running"
    SUCCEEDED = "succeeded"
    FAILED = "failed"
    TIMEOUT = "timeout"
    ABORTED = "aborted"
    SKIPPED = "skipped"
    DROPPED = "dropped"  # by the strategic level, before it began: the budget could not cover it


@dataclass
class ElementReport:
    id: str
    kind: str
    status: ElementStatus
    start_time: float = math.nan
    end_time: float = math.nan
    reason: str = ""
    planned_path: list[tuple[float, float]] = field(default_factory=list)
    details: AgentReport = field(default_factory=AgentReport)
    recorded_pairs: int | None = None  # stereo pairs its `record`/`model` action recorded (`stereo/ID/`)

    @property
    def duration_s(self) -> float:
        return self.end_time - self.start_time if math.isfinite(self.start_time) else 0.0


@dataclass
class ExecutionReport:
    completed: bool = False
    aborted: bool = False
    abort_reason: str = ""
    elements: list[ElementReport] = field(default_factory=list)
    violations: list[dict[str, Any]] = field(default_factory=list)
    start_time: float = 0.0
    end_time: float = 0.0
    knowledge: Knowledge = field(default_factory=Knowledge)
    link_lost: bool = False
    stopped: bool = False  # stopped on request (SIGINT/SIGTERM onboard)
    paused_s: float = 0.0  # time a pilot had the vehicle


def default_timeout(element: RouteElement, nav: NavState, mission: Mission) -> float:
    """The time an element may take when it does not say: twice the nominal time plus a margin, or its budget."""
    if element.timeout is not None:
        return element.timeout
    params = element.params
    if isinstance(params, Transit):
        to = (mission.home.north, mission.home.east) if isinstance(params.to, str) else (params.to.north,
                                                                                          params.to.east)
        speed = params.speed or mission.vehicle.cruise_speed
        horizontal = math.hypot(to[0] - nav.north, to[1] - nav.east) / speed
        vertical = abs((params.depth if params.depth is not None else nav.depth) - nav.depth)
        return 2.0 * (horizontal + vertical / mission.vehicle.max_vertical_speed) + MARGIN_S
    budget = getattr(params, "budget", None)
    return float(budget) * 1.2 + MARGIN_S if budget is not None else mission.safety.max_duration


def timeout_for(element: RouteElement, nav: NavState, mission: Mission, abort_of: ExecutionReport | None = None
                ) -> float:
    """`default_timeout`, and for a leg of an abort (`abort_of`: the run's report) no later than the run's hard end,
    `max_duration + abort_time` after its start (time a pilot held the vehicle excepted)."""
    timeout = default_timeout(element, nav, mission)
    if abort_of is None:
        return timeout
    end = abort_of.start_time + abort_of.paused_s + mission.safety.max_duration + mission.safety.abort_time
    return min(timeout, max(end - nav.time, 0.0))


def unsupported_elements(mission: Mission, agents: Mapping[str, object] | None = None) -> list[RouteElement]:
    """The route elements whose kind has no agent (in `agents`, by default the registry)."""
    kinds = REGISTRY if agents is None else agents
    return [e for e in mission.route if e.kind not in kinds]


class Executive:
    """Runs a mission on a vehicle. `emit(event, time, **fields)` receives every event as it happens."""

    def __init__(self, mission: Mission, vehicle: VehicleInterface, emit: Callable[..., None],
                 agents: Mapping[str, Callable[[], Agent]] | None = None,
                 on_tick: Callable[[NavState], None] | None = None, plugins: PluginHost | None = None,
                 artifacts: Artifacts | None = None):
        self.mission = mission
        self.vehicle = vehicle
        self.emit = emit
        self.agents = dict(REGISTRY if agents is None else agents)
        self.on_tick = on_tick
        self.report = ExecutionReport()
        self.monitors: SafetyMonitors | None = None
        self.usbl_available = mission.sensors.usbl is not None
        self.plugins = plugins
        self.artifacts = artifacts if artifacts is not None else Artifacts()
        self._stop_reason = ""
        self._paused_since: float | None = None
        self._last_nav: NavState | None = None

    def request_stop(self, reason: str = "stopped by the operator") -> None:
        """Ask the run to end at the next control tick (safe to call from a signal handler)."""
        self._stop_reason = reason

    def unsupported(self) -> list[RouteElement]:
        return unsupported_elements(self.mission, self.agents)

    def _violations(self, nav: NavState, element_id: str) -> list[Violation]:
        assert self.monitors is not None
        found = self.monitors.check(nav)
        for v in found:
            record = {"time": nav.time, "monitor": v.monitor, "message": v.message, "element": element_id,
                      "north": nav.north, "east": nav.east, "depth": nav.depth}
            self.report.violations.append(record)
            self.emit("safety_violation", nav.time, **{k: val for k, val in record.items() if k != "time"})
        return found

    def _run(self, element_id: str, kind: str, agent: Agent, element: RouteElement, aborting: bool
             ) -> ElementReport:
        nav = self.vehicle.observe().nav
        rep = ElementReport(element_id, kind, ElementStatus.RUNNING, start_time=nav.time)
        timeout = timeout_for(element, nav, self.mission, self.report if aborting else None)
        try:
            agent.start(AgentContext(self.mission, element, nav, self.emit, self.report.knowledge, self.plugins,
                                     self.artifacts))
            rep.planned_path = [tuple(map(float, p)) for p in agent.planned_path()]  # type: ignore[misc]
        except Exception as exc:  # an agent's fault is the element's failure, never the executive's crash
            rep.status, rep.reason, rep.end_time = ElementStatus.FAILED, f"agent failed to start: {exc!r}", nav.time
            self.emit("element_failed", nav.time, element=element_id, kind=kind, reason=rep.reason)
            return rep
        aided = self.usbl_available and agent.navigation == "usbl"
        self.vehicle.set_aiding(aided)
        recording = ElementStereo(self.artifacts.root, element_id, R_body_cam_of(self.mission.sensors.stereo)) \
            if any(a in RECORDING_ACTIONS for a in element.actions) else None
        extra = frozenset({"stereo"}) if recording is not None else frozenset()
        payload, rate = agent.payload, agent.frame_rate_hz
        self.vehicle.set_payload(payload | extra)
        self.vehicle.set_frame_rate(rate)
        self.emit("element_started", nav.time, element=element_id, kind=kind, timeout_s=timeout,
                  navigation="usbl" if aided else "dead-reckoning", planned_path=rep.planned_path, abort=aborting)
        try:
            self._loop(rep, agent, element_id, timeout, aborting, payload, rate, aided, recording)
        except LinkLostError as exc:
            rep.status, rep.reason = ElementStatus.ABORTED, f"link lost: {exc}"
            self.report.link_lost = True
        finally:
            if recording is not None:
                recording.close()
                rep.recorded_pairs = recording.pairs
        nav = self._last_nav if self._last_nav is not None else nav
        try:
            agent.stop()
        except Exception as exc:
            self.emit("agent_fault", nav.time, element=element_id, error=repr(exc))
        if not self.report.link_lost:
            self.vehicle.set_payload(frozenset())
            self.vehicle.set_frame_rate(None)
        if self.plugins is not None:
            self.plugins.reset()
        rep.end_time = nav.time
        rep.details = agent.details
        event = "element_finished" if rep.status is ElementStatus.SUCCEEDED else "element_failed"
        self.emit(event, nav.time, element=element_id, kind=kind, status=rep.status, reason=rep.reason,
                  duration_s=rep.duration_s, north=nav.north, east=nav.east, depth=nav.depth)
        return rep

    def _paused(self, obs: Observation, element_id: str) -> bool:
        """Track a pilot's take-over: True while the vehicle is not ours (the agent is not stepped)."""
        now = obs.nav.time
        if not obs.in_control:
            if self._paused_since is None:
                self._paused_since = now
                self.emit("mission_paused", now, element=element_id, reason="a pilot took the vehicle over")
            return True
        if self._paused_since is not None:
            held = now - self._paused_since
            self.report.paused_s += held
            self._paused_since = None
            self.emit("mission_resumed", now, element=element_id, paused_s=held)
        return False

    def _loop(self, rep: ElementReport, agent: Agent, element_id: str, timeout: float, aborting: bool,
              payload: frozenset[str], rate: float | None, aided: bool, recording: ElementStereo | None = None
              ) -> None:
        """Step the agent every control tick until it ends, times out, trips a monitor or is stopped; with
        `recording`, the stereo camera stays on and every pair is recorded."""
        paused_at_start = self.report.paused_s
        extra = frozenset({"stereo"}) if recording is not None else frozenset()
        while True:
            obs = self.vehicle.observe()
            nav = obs.nav
            self._last_nav = nav
            if recording is not None:
                recording.add(obs)
            if self._paused(obs, element_id):
                self._violations(nav, element_id)  # logged; the pilot is responsible while in control
                self.vehicle.advance()
                continue
            if self._violations(nav, element_id) and not aborting:
                rep.status, rep.reason = ElementStatus.ABORTED, "safety violation"
                return
            if self._stop_reason and not aborting:
                rep.status, rep.reason = ElementStatus.ABORTED, self._stop_reason
                return
            if nav.time - rep.start_time - (self.report.paused_s - paused_at_start) > timeout:
                rep.status, rep.reason = ElementStatus.TIMEOUT, f"not finished within {timeout:.0f} s"
                return
            try:
                command = agent.step(obs)
            except Exception as exc:
                rep.status, rep.reason = ElementStatus.FAILED, f"agent fault: {exc!r}"
                self.emit("agent_fault", nav.time, element=element_id, error=repr(exc))
                return
            if agent.status is Status.SUCCEEDED:
                rep.status = ElementStatus.SUCCEEDED
                return
            if agent.status is Status.FAILED:
                rep.status, rep.reason = ElementStatus.FAILED, agent.reason
                return
            if agent.payload != payload:
                payload = agent.payload
                self.vehicle.set_payload(payload | extra)
            if (self.usbl_available and agent.navigation == "usbl") != aided:
                aided = self.usbl_available and agent.navigation == "usbl"
                self.vehicle.set_aiding(aided)
                self.emit("navigation_changed", nav.time, element=element_id,
                          navigation="usbl" if aided else "dead-reckoning")
            if agent.frame_rate_hz != rate:
                rate = agent.frame_rate_hz
                self.vehicle.set_frame_rate(rate)
            self.vehicle.apply(command)
            self.vehicle.advance()
            if self.on_tick is not None:
                self.on_tick(nav)

    def _abort(self, reason: str) -> None:
        """Go to the abort point at a safe depth, then surface there (per `safety.on_violation`)."""
        nav = self.vehicle.observe().nav
        self.report.aborted, self.report.abort_reason = True, reason
        self.emit("abort", nav.time, reason=reason, abort_to=policy_record(self.mission)["abort_to"])
        for leg_id, params in abort_legs(self.mission, nav, self.usbl_available):
            element = RouteElement(id=leg_id, transit=params)
            self.report.elements.append(self._run(leg_id, "transit", TransitAgent(params), element, aborting=True))

    def run(self) -> ExecutionReport:
        """Run the whole route; returns what happened (the event log has the details)."""
        m = self.mission
        nav = self.vehicle.observe().nav
        self._last_nav = nav
        self.monitors = SafetyMonitors(m.safety, m.vehicle.energy_wh, nav.time)
        self.report.start_time = nav.time
        self.emit("mission_started", nav.time, mission=m.name, elements=[e.id for e in m.route])
        abort_reason = self._route()
        if abort_reason and not self.report.link_lost and not self._stop_reason:
            try:
                self._abort(abort_reason)
            except LinkLostError:
                self.report.link_lost = True
        nav = self._last_nav
        if self.report.link_lost:
            self._lost(nav)
        else:
            self._finish_safe(nav)
        self.report.end_time = nav.time
        self.report.completed = not abort_reason and not self.report.link_lost and all(
            r.status in (ElementStatus.SUCCEEDED, ElementStatus.DROPPED) for r in self.report.elements)
        self.emit("mission_finished", nav.time, completed=self.report.completed, aborted=self.report.aborted,
                  reason=self.report.abort_reason)
        return self.report

    def _route(self) -> str:
        """Run the route as the strategic level plans it (`mission.strategy`: before the first element and again
        after each, on what is left); the reason to abort, or "" when every element had its chance."""
        abort_reason = ""
        strategy = StrategicLevel(self.mission, self.emit, self.report.start_time)
        while not abort_reason and self._last_nav is not None and (element := strategy.next(self._last_nav)):
            rep = self._element(element, self._last_nav)
            self.report.elements.append(rep)
            if self.report.link_lost:
                abort_reason = f"link lost during '{element.id}'"
            elif self._stop_reason:
                abort_reason = self._stop_reason
            elif rep.status is ElementStatus.ABORTED:
                abort_reason = "; ".join(v["message"] for v in self.report.violations[-3:])
            elif rep.status is not ElementStatus.SUCCEEDED and element.on_failure == "abort":
                abort_reason = f"element '{element.id}' {rep.status}: {rep.reason}"
        for element in strategy.skip_rest():
            status, why = next(((ElementStatus.DROPPED, why) for e, why in strategy.dropped if e is element),
                               (ElementStatus.SKIPPED, ""))
            self.report.elements.append(ElementReport(element.id, element.kind, status, reason=why))
        if abort_reason:
            self.report.abort_reason = abort_reason
        return abort_reason

    def _element(self, element: RouteElement, nav: NavState) -> ElementReport:
        """Create the element's agent and run it; a broken agent class fails its element, not the executive."""
        factory = self.agents.get(element.kind)
        reason = f"no agent for kind '{element.kind}'"
        if factory is not None:
            try:
                return self._run(element.id, element.kind, factory(), element, aborting=False)
            except LinkLostError:
                raise
            except Exception as exc:
                reason = f"agent could not be created: {exc!r}"
        self.emit("element_failed", nav.time, element=element.id, kind=element.kind, reason=reason)
        return ElementReport(element.id, element.kind, ElementStatus.FAILED, nav.time, nav.time, reason=reason)

    def _lost(self, nav: NavState) -> None:
        """The link is gone: nothing can be commanded any more. Log what the mission asked for on a violation."""
        self.report.aborted = True
        self.report.abort_reason = self.report.abort_reason or "link lost"
        self.emit("link_lost", nav.time, timeout_s=self.mission.safety.link_timeout,
                  on_violation=policy_record(self.mission),
                  note="the vehicle's own failsafe takes over; the mission's policy cannot be carried out")

    def _finish_safe(self, nav: NavState) -> None:
        """Leave the vehicle holding; after a stop request, surface it if the mission says so."""
        try:
            self.vehicle.apply(Command.hold(nav))
            if self._stop_reason:
                self.report.stopped = self.report.aborted = True
                surface = self.mission.safety.on_violation.surface
                self.emit("stopped", nav.time, reason=self._stop_reason, surface=surface)
                if surface:
                    self.vehicle.apply(Command(heading=nav.heading, speed=0.0, depth=0.0))
        except LinkLostError:
            self.report.link_lost = True
            self._lost(nav)
