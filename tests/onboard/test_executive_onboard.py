"""The executive onboard: a pilot's take-over pauses the mission, a lost link ends it with the policy logged, and a
stop request leaves the vehicle holding (then surfacing when the mission says so). No simulator is involved."""

from __future__ import annotations

import math
from collections.abc import Callable

from mission import load_mission
from mission.errors import LinkLostError
from mission.events import EventLog
from mission.executive import ElementStatus, Executive
from mission.vehicle import Command, NavState, Observation

ROUTE = """
  - id: out
    transit: {to: {north: 40, east: 0}, depth: 10}
  - id: back
    transit: {to: {north: 0, east: 0}, depth: 10}
"""


class PointMass:
    """A vehicle double: moves at the commanded speed and heading, reaches the commanded depth at 0.5 m/s; its
    estimate is its truth. `script(vehicle)` runs every tick and may take the vehicle away or cut the link."""

    control_period = 0.5

    def __init__(self, script: Callable[[PointMass], None] = lambda v: None):
        self.time, self.north, self.east, self.depth, self.heading, self.speed = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        self.command = Command(0.0, 0.0, 0.0)
        self.commands: list[tuple[float, Command]] = []
        self.in_control = True
        self.link_up = True
        self.script = script

    def observe(self) -> Observation:
        if not self.link_up:
            raise LinkLostError("no heartbeat for 3.0 s")
        nav = NavState(self.time, self.north, self.east, self.depth, self.heading, self.speed, 20.0, 0.5, 3900.0)
        return Observation(nav, in_control=self.in_control)

    def apply(self, command: Command) -> None:
        self.command = command
        self.commands.append((self.time, command))

    def set_aiding(self, usbl: bool) -> None: ...

    def set_payload(self, sensors: frozenset[str]) -> None: ...

    def set_frame_rate(self, rate_hz: float | None) -> None: ...

    def advance(self) -> None:
        if not self.link_up:
            raise LinkLostError("no heartbeat for 3.0 s")
        dt = self.control_period
        if self.in_control:
            c = self.command
            self.heading, self.speed = c.heading, c.speed
            if c.depth is not None:
                self.depth += max(-0.5 * dt, min(0.5 * dt, c.depth - self.depth))
        else:
            self.speed = 0.0  # the pilot holds it
        self.north += self.speed * dt * math.cos(math.radians(self.heading))
        self.east += self.speed * dt * math.sin(math.radians(self.heading))
        self.time += dt
        self.script(self)


def run(write_mission, script, **executive_options) -> tuple[Executive, PointMass, list[dict]]:
    mission = load_mission(write_mission("onboard", ROUTE))
    vehicle = PointMass(script)
    log = EventLog()
    executive = Executive(mission, vehicle, log.emit, **executive_options)
    executive.run()
    return executive, vehicle, log.events


def test_a_pilot_taking_over_pauses_the_mission_and_it_goes_on_when_handed_back(write_mission):
    def pilot(v: PointMass) -> None:
        v.in_control = not (10.0 <= v.time < 40.0)

    executive, vehicle, events = run(write_mission, pilot)
    report = executive.report
    assert report.completed
    names = [e["event"] for e in events]
    assert names.count("mission_paused") == 1 and names.count("mission_resumed") == 1
    resumed = next(e for e in events if e["event"] == "mission_resumed")
    assert abs(resumed["paused_s"] - 30.0) <= vehicle.control_period
    assert abs(report.paused_s - 30.0) <= vehicle.control_period
    # nothing was commanded while the pilot had the vehicle
    assert not [t for t, _ in vehicle.commands if 10.0 + vehicle.control_period <= t < 40.0]


def test_the_pause_does_not_count_against_the_element_timeout(write_mission):
    def pilot(v: PointMass) -> None:
        v.in_control = not (5.0 <= v.time < 205.0)  # longer than the first leg's default timeout

    executive, _, _ = run(write_mission, pilot)
    assert [e.status for e in executive.report.elements] == [ElementStatus.SUCCEEDED, ElementStatus.SUCCEEDED]


def test_a_lost_link_ends_the_run_with_the_policy_logged_and_the_rest_skipped(write_mission):
    def cut(v: PointMass) -> None:
        if v.time >= 20.0:
            v.link_up = False

    executive, _, events = run(write_mission, cut)
    report = executive.report
    assert report.link_lost and report.aborted and not report.completed
    assert [e.status for e in report.elements] == [ElementStatus.ABORTED, ElementStatus.SKIPPED]
    lost = [e for e in events if e["event"] == "link_lost"]
    assert len(lost) == 1 and lost[0]["on_violation"]["abort_to"] == "home"
    assert events[-1]["event"] == "mission_finished" and events[-1]["completed"] is False
    assert not any(e["event"] == "abort" for e in events)  # nothing can be commanded any more


def test_a_stop_request_holds_the_vehicle_and_surfaces_it_when_the_mission_says_so(write_mission):
    holder: dict[str, Executive] = {}

    def operator(v: PointMass) -> None:
        if v.time >= 15.0:
            holder["executive"].request_stop("stopped by SIGINT")

    mission = load_mission(write_mission("stop", ROUTE))
    assert mission.safety.on_violation.surface  # the default policy surfaces
    vehicle = PointMass(operator)
    log = EventLog()
    executive = Executive(mission, vehicle, log.emit)
    holder["executive"] = executive
    report = executive.run()
    assert report.stopped and not report.completed
    assert [e.status for e in report.elements] == [ElementStatus.ABORTED, ElementStatus.SKIPPED]
    assert report.elements[0].reason == "stopped by SIGINT"
    last_two = [c for _, c in vehicle.commands[-2:]]
    assert last_two[0].speed == 0.0 and last_two[0].depth == vehicle.depth  # hold where it is
    assert last_two[1].depth == 0.0  # then surface
    assert not any(e["event"] == "abort" for e in log.events)
    assert any(e["event"] == "stopped" and e["surface"] is True for e in log.events)
