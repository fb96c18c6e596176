"""The strategic level (seed 002 §1): run the route elements in order, one tactical agent each, under the
safety monitors; log every event as it happens; on a violation, abort per the mission's `on_violation`.

The executive sees only the vehicle interface (the estimate), never the simulator or plotting.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

from mission.agents import REGISTRY, Agent, AgentContext, AgentReport, Status
from mission.agents.transit import TransitAgent
from mission.artifacts import Artifacts
from mission.knowledge import Knowledge
from mission.language.models import Mission, RouteElement, Transit
from mission.plugin_host import PluginHost
from mission.safety import SafetyMonitors, Violation
from mission.strategy import inspection_run, order_objects
from mission.vehicle import Command, NavState, VehicleInterface

MARGIN_S = 120.0  # extra time every default timeout allows


@dataclass
class ElementReport:
    id: str
    kind: str
    status: str  # succeeded | failed | timeout | aborted | skipped
    start_time: float = math.nan
    end_time: float = math.nan
    reason: str = ""
    planned_path: list[tuple[float, float]] = field(default_factory=list)
    details: AgentReport = field(default_factory=AgentReport)

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

    def unsupported(self) -> list[RouteElement]:
        return [e for e in self.mission.route if e.kind not in self.agents]

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
        rep = ElementReport(element_id, kind, "running", start_time=nav.time)
        timeout = default_timeout(element, nav, self.mission)
        try:
            agent.start(AgentContext(self.mission, element, nav, self.emit, self.report.knowledge, self.plugins,
                                     self.artifacts))
            rep.planned_path = [tuple(map(float, p)) for p in agent.planned_path()]  # type: ignore[misc]
        except Exception as exc:  # an agent's fault is the element's failure, never the executive's crash
            rep.status, rep.reason, rep.end_time = "failed", f"agent failed to start: {exc!r}", nav.time
            self.emit("element_failed", nav.time, element=element_id, kind=kind, reason=rep.reason)
            return rep
        aided = self.usbl_available and agent.navigation == "usbl"
        self.vehicle.set_aiding(aided)
        payload, rate = agent.payload, agent.frame_rate_hz
        self.vehicle.set_payload(payload)
        self.vehicle.set_frame_rate(rate)
        self.emit("element_started", nav.time, element=element_id, kind=kind, timeout_s=timeout,
                  navigation="usbl" if aided else "dead-reckoning", planned_path=rep.planned_path, abort=aborting)
        while True:
            obs = self.vehicle.observe()
            nav = obs.nav
            if self._violations(nav, element_id) and not aborting:
                rep.status, rep.reason = "aborted", "safety violation"
                break
            if nav.time - rep.start_time > timeout:
                rep.status, rep.reason = "timeout", f"not finished within {timeout:.0f} s"
                break
            try:
                command = agent.step(obs)
            except Exception as exc:
                rep.status, rep.reason = "failed", f"agent fault: {exc!r}"
                self.emit("agent_fault", nav.time, element=element_id, error=repr(exc))
                break
            if agent.status is Status.SUCCEEDED:
                rep.status = "succeeded"
                break
            if agent.status is Status.FAILED:
                rep.status, rep.reason = "failed", agent.reason
                break
            if agent.payload != payload:
                payload = agent.payload
                self.vehicle.set_payload(payload)
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
        try:
            agent.stop()
        except Exception as exc:
            self.emit("agent_fault", nav.time, element=element_id, error=repr(exc))
        self.vehicle.set_payload(frozenset())
        self.vehicle.set_frame_rate(None)
        if self.plugins is not None:
            self.plugins.reset()
        rep.end_time = nav.time
        rep.details = agent.details
        event = "element_finished" if rep.status == "succeeded" else "element_failed"
        self.emit(event, nav.time, element=element_id, kind=kind, status=rep.status, reason=rep.reason,
                  duration_s=rep.duration_s, north=nav.north, east=nav.east, depth=nav.depth)
        return rep

    def _abort(self, reason: str) -> None:
        """Go to the abort point at a safe depth, then surface there (per `safety.on_violation`)."""
        m = self.mission
        policy = m.safety.on_violation
        nav = self.vehicle.observe().nav
        self.report.aborted, self.report.abort_reason = True, reason
        self.emit("abort", nav.time, reason=reason, abort_to=policy.abort_to if isinstance(policy.abort_to, str)
                  else policy.abort_to.model_dump())
        if isinstance(policy.abort_to, str):
            to: Any = "home"
            final_depth = m.home.depth
        else:
            to = {"north": policy.abort_to.north, "east": policy.abort_to.east}
            final_depth = policy.abort_to.depth
        safe_depth = min(nav.depth, 0.9 * m.safety.max_depth)
        if nav.altitude is not None and nav.altitude < m.safety.min_altitude + 2.0:
            safe_depth = max(0.0, safe_depth - (m.safety.min_altitude + 2.0 - nav.altitude))
        navigation: Literal["usbl", "dead-reckoning"] = "usbl" if self.usbl_available else "dead-reckoning"
        legs = [("abort-return", Transit(to=to, depth=safe_depth, navigation=navigation))]
        if policy.surface:
            legs.append(("abort-surface", Transit(to=to, depth=final_depth, navigation=navigation)))
        for leg_id, params in legs:
            element = RouteElement(id=leg_id, transit=params)
            self.report.elements.append(self._run(leg_id, "transit", TransitAgent(params), element, aborting=True))

    def run(self) -> ExecutionReport:
        """Run the whole route; returns what happened (the event log has the details)."""
        m = self.mission
        nav = self.vehicle.observe().nav
        self.monitors = SafetyMonitors(m.safety, m.vehicle.energy_wh, nav.time)
        self.report.start_time = nav.time
        self.emit("mission_started", nav.time, mission=m.name, elements=[e.id for e in m.route])
        abort_reason = ""
        route = list(m.route)
        for index in range(len(route)):
            end = inspection_run(route, index)
            if end - index >= 2 and (index == 0 or route[index - 1].inspect is None):
                nav = self.vehicle.observe().nav
                ordered = order_objects(m, route[index:end], nav.north, nav.east, m.seed)
                if ordered != route[index:end]:
                    route[index:end] = ordered
                    self.emit("route_reordered", nav.time, elements=[e.id for e in route],
                              reason="inspections in the shortest visiting order")
            element = route[index]
            if abort_reason:
                self.report.elements.append(ElementReport(element.id, element.kind, "skipped"))
                continue
            factory = self.agents.get(element.kind)
            if factory is None:
                rep = ElementReport(element.id, element.kind, "failed", nav.time, nav.time,
                                    reason=f"no agent for kind '{element.kind}'")
                self.emit("element_failed", nav.time, element=element.id, kind=element.kind, reason=rep.reason)
            else:
                try:
                    agent = factory()
                except Exception as exc:  # a broken agent class fails its element, not the executive
                    agent = None
                    rep = ElementReport(element.id, element.kind, "failed", nav.time, nav.time,
                                        reason=f"agent could not be created: {exc!r}")
                    self.emit("element_failed", nav.time, element=element.id, kind=element.kind, reason=rep.reason)
                if agent is not None:
                    rep = self._run(element.id, element.kind, agent, element, aborting=False)
            self.report.elements.append(rep)
            if rep.status == "aborted":
                abort_reason = "; ".join(v["message"] for v in self.report.violations[-3:])
            elif rep.status != "succeeded" and element.on_failure == "abort":
                abort_reason = f"element '{element.id}' {rep.status}: {rep.reason}"
        if abort_reason:
            self._abort(abort_reason)
        nav = self.vehicle.observe().nav
        self.vehicle.apply(Command.hold(nav))
        self.report.end_time = nav.time
        self.report.completed = not abort_reason and all(
            r.status == "succeeded" for r in self.report.elements)
        self.emit("mission_finished", nav.time, completed=self.report.completed, aborted=self.report.aborted,
                  reason=self.report.abort_reason)
        return self.report
