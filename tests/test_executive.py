"""The executive contains agent faults, logs events as they happen, times out, aborts to safety, and refuses
unsupported kinds. It runs here on the library's test doubles (`mission.testing`): no simulator, no MuJoCo."""

import json
import math
import subprocess
import sys
import textwrap

from mission import load_mission
from mission.agents import REGISTRY, Agent, TransitAgent
from mission.events import EventLog
from mission.executive import Executive
from mission.testing import FakeAgent, FakeStep, StubVehicle, take_from
from mission.vehicle import Command

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


def run_with(mission, agents, vehicle=None, log=None):
    vehicle = vehicle or StubVehicle.for_mission(mission)
    log = log or EventLog()
    report = Executive(mission, vehicle, log.emit, agents=agents).run()
    return report, log.events


def test_an_agent_fault_fails_its_element_and_the_mission_goes_on(write_mission):
    mission = load_mission(write_mission("fault", ROUTE))
    vehicle = StubVehicle.for_mission(mission)
    report, events = run_with(mission, {"transit": take_from(ExplodingAgent(), TransitAgent())}, vehicle)
    assert [e.status for e in report.elements] == ["failed", "succeeded"]
    assert "sonar driver crashed" in report.elements[0].reason
    assert any(e["event"] == "agent_fault" and e["element"] == "first" for e in events)
    assert not report.completed and not report.aborted
    # the second transit still reached its point: the stub's estimate is its truth
    assert math.hypot(vehicle.north - 60, vehicle.east - 30) < 5.0 and abs(vehicle.depth - 10) < 1.0


def test_an_agent_that_cannot_start_is_a_failed_element(write_mission):
    mission = load_mission(write_mission("nostart", ROUTE))
    agents = take_from(*(FakeAgent(raise_on_start=ValueError("no plan")) for _ in range(2)))
    report, events = run_with(mission, {"transit": agents})
    assert [e.status for e in report.elements] == ["failed", "failed"]
    assert "no plan" in report.elements[0].reason
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


def test_each_element_gets_its_payload_and_aiding_and_both_are_released_when_it_ends(write_mission):
    mission = load_mission(write_mission("payload", ROUTE))
    first = FakeAgent([FakeStep(5)], payload=["stereo"], navigation="dead-reckoning")
    second = FakeAgent([FakeStep(5)], payload=["mbes"])
    vehicle = StubVehicle.for_mission(mission)
    report, _ = run_with(mission, {"transit": take_from(first, second)}, vehicle)
    assert [e.status for e in report.elements] == ["succeeded", "succeeded"]
    assert [p for _, p in vehicle.payloads] == [{"stereo"}, set(), {"mbes"}, set()]
    assert [a for _, a in vehicle.aiding] == [False, True]
    assert first.stopped and second.stopped and len(first.observations) == 6  # 5 scripted ticks, then it succeeds


def test_an_element_that_overruns_its_timeout_ends_at_the_timeout(write_mission):
    route = """
  - id: endless
    transit: {to: {north: 30, east: 30}, depth: 10}
    timeout: 20
"""
    mission = load_mission(write_mission("timeout", route))
    agent = FakeAgent(outcome="run")
    report, _ = run_with(mission, {"transit": take_from(agent)})
    (element,) = report.elements
    assert element.status == "timeout" and agent.stopped
    assert 20.0 < element.duration_s <= 20.0 + 2 * StubVehicle().control_period


def test_a_depth_violation_aborts_the_mission_and_the_vehicle_returns_home_and_surfaces(write_mission):
    route = """
  - id: dive
    transit: {to: {north: 30, east: 30}, depth: 10}
    timeout: 1000
  - id: never
    transit: {to: {north: 60, east: 30}, depth: 10}
"""
    mission = load_mission(write_mission("abort", route))
    too_deep = FakeAgent([FakeStep(100_000, Command(heading=0.0, speed=0.0, depth=130.0))], outcome="run")
    vehicle = StubVehicle.for_mission(mission, seabed_depth=200.0)
    agents = {"transit": take_from(too_deep, FakeAgent())}  # the abort legs are the executive's own transits
    report, events = run_with(mission, agents, vehicle)
    assert report.aborted and not report.completed
    assert [(e.id, e.status) for e in report.elements] == [
        ("dive", "aborted"), ("never", "skipped"), ("abort-return", "succeeded"), ("abort-surface", "succeeded")]
    assert any(e["event"] == "safety_violation" and e["monitor"] == "max_depth" for e in events)
    # it stopped going down within a tick of the limit, and ended at home on the surface
    assert max(e["depth"] for e in events if e["event"] == "safety_violation") < 120.0 + 0.5
    assert math.hypot(vehicle.north - mission.home.north, vehicle.east - mission.home.east) < 5.0
    assert vehicle.depth < 1.0


def test_events_are_on_disk_as_soon_as_they_are_emitted(tmp_path):
    path = tmp_path / "events.jsonl"
    log = EventLog(path)
    log.emit("element_started", 1.5, element="a")
    first = path.read_text().splitlines()
    assert json.loads(first[0]) == {"time": 1.5, "event": "element_started", "element": "a"}
    log.emit("element_finished", 2.0, element="a")
    assert len(path.read_text().splitlines()) == 2
    log.close()


def test_the_executive_writes_events_while_the_mission_runs(write_mission, tmp_path):
    mission = load_mission(write_mission("live", ROUTE))
    path = tmp_path / "events.jsonl"
    seen = []

    class Peeking(FakeAgent):
        def start(self, context):
            seen.append([json.loads(line)["event"] for line in path.read_text().splitlines()])
            super().start(context)

    log = EventLog(path)
    run_with(mission, {"transit": take_from(Peeking([FakeStep(3)]), Peeking([FakeStep(3)]))}, log=log)
    log.close()
    assert seen[0] == ["mission_started"]
    assert seen[1][-2:] == ["element_started", "element_finished"]  # the first element's events, on disk


def test_kinds_without_an_agent_are_listed_before_anything_starts(write_mission):
    route = ROUTE + """
  - id: look
    explore: {object: detected, sensor: scanner}
"""
    path = write_mission("unsupported", route)
    path.write_text(path.read_text().replace(
        "usbl: {sigma: 1.5, rate_hz: 0.5}", "usbl: {sigma: 1.5, rate_hz: 0.5}\n  scanner: {max_range: 10}"))
    mission = load_mission(path)
    vehicle = StubVehicle.for_mission(mission)
    executive = Executive(mission, vehicle, EventLog().emit, agents={"transit": TransitAgent})
    assert [e.id for e in executive.unsupported()] == ["look"]
    assert Executive(mission, vehicle, EventLog().emit, agents=REGISTRY).unsupported() == []
    assert vehicle.commands == []  # nothing ran


def test_the_executive_runs_on_the_stub_with_mujoco_and_matplotlib_unimportable(write_mission):
    path = write_mission("nomujoco", ROUTE)
    code = textwrap.dedent(f"""
        import sys

        class Block:  # as if neither were installed
            def find_spec(self, name, path=None, target=None):
                if name.split(".")[0] in ("mujoco", "matplotlib"):
                    raise ImportError(f"{{name}} is not installed")
                return None

        sys.meta_path.insert(0, Block())
        from mission import load_mission
        from mission.events import EventLog
        from mission.executive import Executive
        from mission.testing import StubVehicle

        mission = load_mission({str(path)!r})
        report = Executive(mission, StubVehicle.for_mission(mission), EventLog().emit).run()
        loaded = sorted(m for m in sys.modules if m.split(".")[0] in ("mujoco", "matplotlib")
                        or m.startswith("mission.sim"))
        print(report.completed, [str(e.status.value) for e in report.elements], loaded)
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "True ['succeeded', 'succeeded'] []"
