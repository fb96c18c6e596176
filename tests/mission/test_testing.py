"""The shipped test doubles behave as documented: the stub vehicle's kinematics and scripted faults, the scripted
plug-in and the fake agent."""

import math
import time

import pytest

from mission.errors import LinkLostError
from mission.language.models import VehicleSettings
from mission.plugin_api import PerceptionPlugin, ReferencingResult
from mission.testing import FakeAgent, FakeStep, ScriptedPlugin, StubFaults, StubVehicle, blank_frame, take_from
from mission.vehicle import STATION_KEEPING_SPEED_M_S, Command


def run(vehicle: StubVehicle, command: Command, seconds: float) -> None:
    vehicle.apply(command)
    for _ in range(round(seconds / vehicle.control_period)):
        vehicle.advance()


def test_the_stub_turns_no_faster_than_its_yaw_rate_limit_and_reaches_the_commanded_heading():
    vehicle = StubVehicle(limits=VehicleSettings(max_yaw_rate=10.0), control_period=0.1)
    run(vehicle, Command(heading=90.0, speed=0.0, depth=0.0), 5.0)
    assert vehicle.heading == pytest.approx(50.0, abs=1e-9)  # 10 °/s for 5 s: still saturated
    run(vehicle, Command(heading=90.0, speed=0.0, depth=0.0), 30.0)
    assert vehicle.heading == pytest.approx(90.0, abs=0.01)


def test_the_stub_holds_a_commanded_altitude_over_its_flat_seabed_at_the_vertical_speed_limit():
    vehicle = StubVehicle(seabed_depth=40.0, control_period=0.5)
    run(vehicle, Command(heading=0.0, speed=0.0, altitude=5.0), 20.0)
    assert vehicle.depth == pytest.approx(10.0, abs=1e-9)  # 0.5 m/s for 20 s
    run(vehicle, Command(heading=0.0, speed=0.0, altitude=5.0), 200.0)
    assert vehicle.observe().nav.altitude == pytest.approx(5.0, abs=0.01)


def test_the_stub_station_keeps_at_hover_speed_and_stops_on_the_station():
    vehicle = StubVehicle(control_period=0.2)
    run(vehicle, Command(heading=0.0, speed=1.5, depth=0.0, station=(10.0, 0.0)), 10.0)
    assert vehicle.north == pytest.approx(STATION_KEEPING_SPEED_M_S * 10.0, abs=1e-6)
    run(vehicle, Command(heading=0.0, speed=1.5, depth=0.0, station=(10.0, 0.0)), 120.0)
    assert math.hypot(vehicle.north - 10.0, vehicle.east) < 0.01


def test_a_lost_link_raises_from_observe_and_advance_once_its_time_has_come():
    vehicle = StubVehicle(control_period=1.0, faults=StubFaults(link_lost_at=3.0))
    run(vehicle, Command(heading=0.0, speed=1.0, depth=0.0), 3.0)
    with pytest.raises(LinkLostError):
        vehicle.observe()
    with pytest.raises(LinkLostError):
        vehicle.advance()


def test_during_a_pilot_takeover_the_stub_is_not_in_control_and_ignores_commands():
    vehicle = StubVehicle(control_period=1.0, faults=StubFaults(pilot_takeover=(2.0, 5.0)))
    run(vehicle, Command(heading=0.0, speed=0.0, depth=0.0), 2.0)
    assert not vehicle.observe().in_control
    run(vehicle, Command(heading=0.0, speed=0.0, depth=10.0), 3.0)  # ignored: applied while taken over
    assert vehicle.depth == 0.0 and vehicle.observe().in_control
    assert len(vehicle.commands) == 2  # both were recorded


def test_an_energy_drain_fault_adds_to_the_power_the_stub_draws():
    normal, drained = StubVehicle(control_period=1.0), StubVehicle(control_period=1.0,
                                                                     faults=StubFaults(energy_drain_wh_per_s=2.0))
    for v in (normal, drained):
        run(v, Command(heading=0.0, speed=0.0, depth=0.0), 60.0)
    hotel_wh = VehicleSettings().hotel_power_w * 60.0 / 3600.0
    assert normal.energy_used_wh == pytest.approx(hotel_wh)
    assert drained.observe().nav.energy_wh == pytest.approx(normal.observe().nav.energy_wh - 120.0)


def test_the_scripted_plugin_is_a_perception_plugin_that_sleeps_before_it_answers():
    plugin = ScriptedPlugin([ReferencingResult(True, set_id="a")], sleep_s=0.05)
    assert isinstance(plugin, PerceptionPlugin)
    t0 = time.perf_counter()
    assert plugin.process(blank_frame(1.0), "request").set_id == "a"
    assert time.perf_counter() - t0 >= 0.05
    plugin.reset()
    plugin.close()
    assert (plugin.frames, plugin.requests, plugin.resets, plugin.closed) == ([1.0], ["request"], 1, 1)


def test_the_fake_agent_plays_its_script_then_fails_with_its_reason():
    vehicle = StubVehicle()
    agent = FakeAgent([FakeStep(2, Command(heading=45.0, speed=1.0, depth=5.0))], outcome="fail", reason="lost")
    commands = [agent.step(vehicle.observe()) for _ in range(3)]
    assert [c.heading for c in commands[:2]] == [45.0, 45.0] and commands[2].speed == 0.0
    assert agent.status.value == "failed" and agent.reason == "lost"


def test_take_from_hands_out_its_agents_in_turn_and_refuses_a_third():
    a, b = FakeAgent(), FakeAgent()
    factory = take_from(a, b)
    assert factory() is a and factory() is b
    with pytest.raises(RuntimeError):
        factory()
