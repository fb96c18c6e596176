"""Kinematic vehicle model: speed, acceleration, yaw-rate (and turning-radius), vertical-rate limits, and the
water current carrying the vehicle. Scalar math only: the simulator calls this every step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from mission.frames import wrap_deg
from mission.language.models import VehicleSettings

YAW_GAIN = 1.0  # (deg/s) per deg of heading error
DEPTH_GAIN = 0.4  # (m/s) per m of depth error


@dataclass
class TrueState:
    time: float
    north: float
    east: float
    depth: float
    heading: float  # deg
    speed: float  # through the water, m/s
    v_north: float = 0.0  # over ground
    v_east: float = 0.0
    v_down: float = 0.0


def step(state: TrueState, heading_cmd: float, speed_cmd: float, depth_cmd: float, heading_meas: float,
         depth_meas: float, limits: VehicleSettings, current: tuple[float, float], dt: float,
         hover_velocity: tuple[float, float] | None = None) -> None:
    """Advance the true state by dt towards the setpoints; the autopilot closes its loops on measurements.

    With `hover_velocity` (north, east over ground, m/s) the vehicle station-keeps: its thrusters hold that
    ground velocity against the current (the DVL measures velocity over ground), whatever the heading."""
    target = min(max(speed_cmd, 0.0), limits.max_speed)
    dv = limits.max_acceleration * dt
    state.speed += min(max(target - state.speed, -dv), dv)
    rate_limit = limits.max_yaw_rate
    if limits.turn_radius > 0:
        rate_limit = min(rate_limit, math.degrees(max(state.speed, 0.5) / limits.turn_radius))
    rate = min(max(YAW_GAIN * wrap_deg(heading_cmd - heading_meas), -rate_limit), rate_limit)
    state.heading = (state.heading + rate * dt) % 360.0
    w = min(max(DEPTH_GAIN * (depth_cmd - depth_meas), -limits.max_vertical_speed), limits.max_vertical_speed)
    h = math.radians(state.heading)
    if hover_velocity is not None:
        state.speed = math.hypot(*hover_velocity)
        state.v_north, state.v_east = hover_velocity
    else:
        state.v_north = state.speed * math.cos(h) + current[0]
        state.v_east = state.speed * math.sin(h) + current[1]
    state.v_down = w
    state.north += state.v_north * dt
    state.east += state.v_east * dt
    state.depth = max(state.depth + w * dt, 0.0)
    state.time += dt
