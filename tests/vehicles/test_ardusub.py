"""The mapping between our `Command` and ArduSub's GUIDED setpoint, both ways (no link involved)."""

from __future__ import annotations

import math

import pytest

from mission.vehicle import Command
from mission.vehicles import ardusub as sub


def test_a_run_command_becomes_a_position_velocity_target_at_the_wanted_depth_facing_the_heading() -> None:
    sp = sub.setpoint_for(Command(heading=90.0, speed=1.2, depth=25.0), north=10.0, east=-3.0, depth=20.0,
                          altitude=15.0)
    assert sp.type_mask == sub.ACCELERATION | sub.YAW_RATE
    assert (sp.x, sp.y, sp.z) == (10.0, -3.0, 25.0)
    assert sp.vx == pytest.approx(0.0, abs=1e-12) and sp.vy == pytest.approx(1.2)
    assert sp.yaw == pytest.approx(math.pi / 2)


def test_an_altitude_becomes_the_depth_that_puts_the_seabed_that_far_below() -> None:
    sp = sub.setpoint_for(Command(heading=0.0, speed=1.0, altitude=8.0), north=0.0, east=0.0, depth=30.0,
                          altitude=11.5)
    assert sp.z == pytest.approx(33.5)
    no_reading = sub.setpoint_for(Command(heading=0.0, speed=1.0, altitude=8.0), 0.0, 0.0, 30.0, None)
    assert no_reading.z == 30.0  # without a rangefinder reading the depth is kept


def test_neither_depth_nor_altitude_keeps_the_current_depth_and_depth_never_goes_above_the_surface() -> None:
    assert sub.setpoint_for(Command(heading=0.0, speed=1.0), 0.0, 0.0, 12.0, 5.0).z == 12.0
    assert sub.setpoint_for(Command(heading=0.0, speed=1.0, altitude=20.0), 0.0, 0.0, 3.0, 5.0).z == 0.0


def test_a_station_becomes_a_position_target_with_yaw() -> None:
    sp = sub.setpoint_for(Command(heading=200.0, speed=0.7, depth=5.0, station=(4.0, 6.0)), 0.0, 0.0, 5.0, None)
    assert sp.type_mask & sub.VELOCITY == sub.VELOCITY and not sp.type_mask & (sub.POSITION | sub.YAW)
    assert (sp.x, sp.y, sp.z) == (4.0, 6.0, 5.0)


@pytest.mark.parametrize("command", [
    Command(heading=135.0, speed=1.5, depth=40.0),
    Command(heading=350.0, speed=0.0, depth=2.0),
    Command(heading=10.0, speed=0.0, depth=7.5, station=(-3.0, 2.5)),
])
def test_the_vehicle_side_reads_back_the_command_it_was_sent(command: Command) -> None:
    sp = sub.setpoint_for(command, 1.0, 2.0, 9.0, None)
    back = sub.command_from_setpoint(sp, heading_now=0.0)
    assert back is not None
    assert back.heading == pytest.approx(command.heading)
    assert back.speed == pytest.approx(command.speed if command.station is None else 0.0)
    assert back.depth == pytest.approx(command.depth)
    assert back.station == command.station


def test_masks_that_ardusub_ignores_give_no_command() -> None:
    assert sub.command_from_setpoint(sub.Setpoint(sub.POSITION | sub.VELOCITY | sub.ACCELERATION), 0.0) is None
    assert sub.command_from_setpoint(sub.Setpoint(sub.POSITION | sub.YAW_RATE), 0.0) is None  # acceleration used


def test_a_bare_velocity_without_yaw_heads_along_the_velocity_and_keeps_depth() -> None:
    back = sub.command_from_setpoint(sub.Setpoint(sub.POSITION | sub.ACCELERATION | sub.YAW | sub.YAW_RATE,
                                                  vx=-1.0, vy=0.0), heading_now=45.0)
    assert back is not None and back.heading == pytest.approx(180.0) and back.speed == pytest.approx(1.0)
    assert back.depth is None
