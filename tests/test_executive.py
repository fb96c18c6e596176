"""The executive contains agent faults, logs events as they happen, and refuses unsupported kinds."""

import json

import pytest

from mission import load_mission
from mission.agents import REGISTRY, Agent, TransitAgent
from mission.errors import UnsupportedMissionError
from mission.events import EventLog
from mission.executive import Executive
from mission.language.loader import load_world
from mission.sim.run import check_supported, simulate
from mission.sim.vehicle import SimulatedVehicle
from mission.world.scene import build_scene

ROUTE = """
  - id: first
    transit: {to: {north: 30, east: 30}, depth: 10}
  - id: second
    transit: {to: {north: 60, east: 30}, depth: 10}
"""


class ExplodingAgent(TransitAgent):
    def step(self, observation):
        if observation.nav.time > 5.0:
            raise RuntimeError("sonar driver crashed")
        return super().step(observation)


def run_with(mission, agents):
    vehicle = SimulatedVehicle(mission, build_scene(load_world(mission.world)), seed=1)
    log = EventLog()
    report = Executive(mission, vehicle, log.emit, agents=agents).run()
    return report, log.events


def test_an_agent_fault_fails_its_element_and_the_mission_goes_on(write_mission):
    mission = load_mission(write_mission("fault", ROUTE))
    calls = iter([ExplodingAgent, TransitAgent])
    report, events = run_with(mission, {"transit": lambda: next(calls)()})
    assert [e.status for e in report.elements] == ["failed", "succeeded"]
    assert "sonar driver crashed" in report.elements[0].reason
    assert any(e["event"] == "agent_fault" and e["element"] == "first" for e in events)
    assert not report.completed and not report.aborted


def test_an_agent_that_cannot_start_is_a_failed_element(write_mission):
    class Broken(Agent):
        kind = "transit"

        def start(self, context):
            raise ValueError("no plan")

        def step(self, observation):
            raise AssertionError("never called: start failed")

    mission = load_mission(write_mission("nostart", ROUTE))
    report, events = run_with(mission, {"transit": Broken})
    assert [e.status for e in report.elements] == ["failed", "failed"]
    assert events[-1]["event"] == "mission_finished" and events[-1]["completed"] is False


def test_an_agent_class_that_cannot_be_built_fails_its_element_only(write_mission):
    class Incomplete(Agent):  # no step(): abstract, cannot be instantiated
        kind = "transit"

        def start(self, context):
            return None

    mission = load_mission(write_mission("incomplete", ROUTE))
    report, events = run_with(mission, {"transit": Incomplete})
    assert [e.status for e in report.elements] == ["failed", "failed"]
    assert "could not be created" in report.elements[0].reason
    assert events[-1]["event"] == "mission_finished"


def test_events_are_on_disk_as_soon_as_they_are_emitted(tmp_path):
    path = tmp_path / "events.jsonl"
    log = EventLog(path)
    log.emit("element_started", 1.5, element="a")
    first = path.read_text().splitlines()
    assert json.loads(first[0]) == {"time": 1.5, "event": "element_started", "element": "a"}
    log.emit("element_finished", 2.0, element="a")
    assert len(path.read_text().splitlines()) == 2
    log.close()


def test_simulate_writes_events_while_running(write_mission, tmp_path, monkeypatch):
    mission = load_mission(write_mission("live", ROUTE))
    seen = []
    original = REGISTRY["transit"]

    class Peeking(TransitAgent):
        def start(self, context):
            seen.append(len((tmp_path / "run" / "events.jsonl").read_text().splitlines()))
            super().start(context)

    monkeypatch.setitem(REGISTRY, "transit", Peeking)
    simulate(mission, out=tmp_path / "run", plots=False)
    monkeypatch.setitem(REGISTRY, "transit", original)
    assert seen[0] >= 1 and seen[1] > seen[0]  # mission_started, then the first element's events, on disk


def test_unsupported_kinds_are_refused_before_anything_starts(write_mission, monkeypatch):
    monkeypatch.delitem(REGISTRY, "explore")  # every kind has an agent now: pretend this one has none
    route = ROUTE + """
  - id: look
    explore: {object: detected, sensor: scanner}
"""
    path = write_mission("unsupported", route, "sensors_dummy: 1\n")
    path.write_text(path.read_text().replace("sensors_dummy: 1\n", "").replace(
        "usbl: {sigma: 1.5, rate_hz: 0.5}", "usbl: {sigma: 1.5, rate_hz: 0.5}\n  scanner: {max_range: 10}"))
    mission = load_mission(path)
    with pytest.raises(UnsupportedMissionError, match=r"explore .*look \(explore\)"):
        check_supported(mission)
