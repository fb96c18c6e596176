"""The kinematic model respects the vehicle's limits and drifts with the current."""

import math

import pytest

from mission.language.models import VehicleSettings
from mission.sim.kinematics import TrueState, step

LIMITS = VehicleSettings(cruise_speed=1.5, max_speed=2.0, max_acceleration=0.2, max_yaw_rate=15, max_vertical_speed=0.5,
                         turn_radius=6)


def run(state, heading, speed, depth, seconds, current=(0.0, 0.0), dt=0.1):
    headings = []
    for _ in range(int(round(seconds / dt))):
        step(state, heading, speed, depth, state.heading, state.depth, LIMITS, current, dt)
        headings.append(state.heading)
    return headings


def test_speed_ramps_at_the_acceleration_limit_and_saturates_at_max_speed():
    s = TrueState(0, 0, 0, 10, 0, 0.0)
    run(s, 0.0, 5.0, 10.0, 5.0)
    assert s.speed == pytest.approx(1.0, abs=1e-9)
    run(s, 0.0, 5.0, 10.0, 20.0)
    assert s.speed == pytest.approx(2.0)


def test_turn_rate_obeys_the_turning_radius():
    s = TrueState(0, 0, 0, 10, 0, 1.5)
    headings = run(s, 180.0, 1.5, 10.0, 2.0)
    rate = (headings[-1] - headings[-2]) / 0.1
    assert rate == pytest.approx(math.degrees(1.5 / 6.0), rel=1e-6)  # 14.3 deg/s < max_yaw_rate 15


def test_vertical_speed_is_limited():
    s = TrueState(0, 0, 0, 0.0, 0, 0.0)
    run(s, 0.0, 0.0, 50.0, 10.0)
    assert s.depth == pytest.approx(5.0, abs=1e-9)


def test_current_carries_a_stopped_vehicle():
    s = TrueState(0, 0, 0, 10, 0, 0.0)
    run(s, 0.0, 0.0, 10.0, 100.0, current=(0.1, -0.2))
    assert (s.north, s.east) == pytest.approx((10.0, -20.0))
