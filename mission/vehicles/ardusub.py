"""What ArduSub speaks over MAVLink, as plain data: its mode numbers, the GUIDED-mode setpoint it accepts, and the
two mappings between our `Command` and that setpoint (the adapter uses one, `auv sim serve` the other).

Read from ArduPilot's sources (not copied): `ArduSub/mode.h` (custom_mode numbers: STABILIZE 0, ACRO 1,
ALT_HOLD 2, AUTO 3, GUIDED 4, CIRCLE 7, SURFACE 9, POSHOLD 16, MANUAL 19, MOTOR_DETECT 20, SURFTRAK 21);
`ArduSub/GCS_MAVLink_Sub.cpp` (SET_POSITION_TARGET_LOCAL_NED is obeyed only in GUIDED, in MAV_FRAME_LOCAL_NED and
the body/offset frames; a type mask with position only, velocity only, or position + velocity, acceleration
always ignored; yaw and yaw rate honoured; z is down, i.e. depth; a bit set in any of x/y/z ignores the whole
position, so depth cannot be held beside a bare velocity); `ArduSub/mode_guided.cpp` (a velocity setpoint times out
after 3 s without updates; position + velocity feeds a shaped position target with a velocity feed-forward).

The MAVLink common set gives the type-mask bits (POSITION_TARGET_TYPEMASK) and frames. ArduSub's SURFTRAK mode
(hold a rangefinder distance) is a pilot mode that takes no GUIDED setpoints, so altitude-following is mapped
here onto depth: depth = current depth + current altitude − wanted altitude, recomputed every control tick from
the latest rangefinder reading (what `mission.sim.vehicle.SimulatedVehicle` does internally too).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from mission.vehicle import Command

# ArduSub custom_mode numbers (ArduSub/mode.h).
MODES: dict[int, str] = {
    0: "STABILIZE", 1: "ACRO", 2: "ALT_HOLD", 3: "AUTO", 4: "GUIDED", 7: "CIRCLE", 9: "SURFACE", 16: "POSHOLD",
    19: "MANUAL", 20: "MOTOR_DETECT", 21: "SURFTRAK",
}
STABILIZE, ALT_HOLD, GUIDED, SURFACE, POSHOLD, MANUAL = 0, 2, 4, 9, 16, 19

# POSITION_TARGET_TYPEMASK bits (MAVLink common): a set bit means "ignore this field".
X, Y, Z, VX, VY, VZ, AX, AY, AZ, FORCE, YAW, YAW_RATE = (1 << k for k in range(12))
POSITION = X | Y | Z
VELOCITY = VX | VY | VZ
ACCELERATION = AX | AY | AZ
MASK_POSITION_YAW = VELOCITY | ACCELERATION | YAW_RATE  # station: go to (x, y, z), face yaw
MASK_POSVEL_YAW = ACCELERATION | YAW_RATE  # run: a position target moving with the velocity, face yaw
MASK_VELOCITY_YAW = POSITION | ACCELERATION | YAW_RATE  # what a bare velocity command looks like

MAV_FRAME_LOCAL_NED = 1

# EKF source sets (MAV_CMD_SET_EKF_SOURCE_SET param1, 1-based; ArduPilot's EK3_SRC1_* … EK3_SRC3_*).
SOURCE_SET_ACOUSTIC = 1  # EK3_SRC1_POSXY: the acoustic position (USBL/UGPS, fed to ArduSub as GPS)
SOURCE_SET_DEAD_RECKONING = 2  # EK3_SRC2_POSXY none, EK3_SRC2_VELXY the DVL: dead reckoning


def mode_name(custom_mode: int) -> str:
    """ArduSub's name of a custom_mode number.

    >>> mode_name(4), mode_name(99)
    ('GUIDED', 'MODE_99')
    """
    return MODES.get(custom_mode, f"MODE_{custom_mode}")


@dataclass(frozen=True)
class Setpoint:
    """One SET_POSITION_TARGET_LOCAL_NED in MAV_FRAME_LOCAL_NED (metres, m/s, radians; z and vz down)."""

    type_mask: int
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    vx: float = 0.0
    vy: float = 0.0
    vz: float = 0.0
    yaw: float = 0.0


def heading_to_yaw(heading_deg: float) -> float:
    """Heading (degrees clockwise from north) → MAVLink yaw (radians, −π..π].

    >>> round(heading_to_yaw(270.0), 4)
    -1.5708
    """
    return math.atan2(math.sin(math.radians(heading_deg)), math.cos(math.radians(heading_deg)))


def yaw_to_heading(yaw_rad: float) -> float:
    """MAVLink yaw (radians) → heading (degrees clockwise from north, 0..360).

    >>> yaw_to_heading(-math.pi / 2)
    270.0
    """
    return math.degrees(yaw_rad) % 360.0


def target_depth(command: Command, depth: float, altitude: float | None) -> float:
    """The depth to hold for `command`: its depth; for an altitude, the current depth moved by the altitude error
    (the current depth when the rangefinder has no reading); with neither, the current depth.

    >>> target_depth(Command(0.0, 1.0, altitude=8.0), depth=30.0, altitude=11.0)
    33.0
    """
    if command.altitude is not None:
        return depth + (altitude - command.altitude) if altitude is not None else depth
    return command.depth if command.depth is not None else depth


def setpoint_for(command: Command, north: float, east: float, depth: float, altitude: float | None) -> Setpoint:
    """The GUIDED setpoint for a command, given the current estimate (north, east, depth, altitude).

    A station is a position target (x, y, z) with yaw. Otherwise the vehicle runs at `speed` along `heading`:
    a position + velocity target whose position is the current estimate at the wanted depth and whose velocity
    is speed × (cos, sin) heading, so that ArduSub holds depth while it follows the velocity (a bare velocity
    cannot carry a depth there). ArduSub's velocities are over ground; the current is the autopilot's to fight.
    """
    z = max(target_depth(command, depth, altitude), 0.0)
    yaw = heading_to_yaw(command.heading)
    if command.station is not None:
        return Setpoint(MASK_POSITION_YAW, x=command.station[0], y=command.station[1], z=z, yaw=yaw)
    h = math.radians(command.heading)
    speed = max(command.speed, 0.0)
    return Setpoint(MASK_POSVEL_YAW, x=north, y=east, z=z, vx=speed * math.cos(h), vy=speed * math.sin(h),
                    yaw=yaw)


def command_from_setpoint(sp: Setpoint, heading_now: float) -> Command | None:
    """The vehicle side's reading of a setpoint as a `Command` (None for a mask ArduSub ignores: acceleration, or
    neither position nor velocity). Position only → a station; velocity → heading and speed from the velocity
    (heading from yaw when given, else the velocity's direction, else the current heading); z → depth when the
    position is used."""
    m = sp.type_mask
    use_pos, use_vel = not m & POSITION, not m & VELOCITY
    if not m & ACCELERATION or not (use_pos or use_vel):
        return None
    speed = math.hypot(sp.vx, sp.vy) if use_vel else 0.0
    if not m & YAW:
        heading = yaw_to_heading(sp.yaw)
    elif use_vel and speed > 1e-6:
        heading = math.degrees(math.atan2(sp.vy, sp.vx)) % 360.0
    else:
        heading = heading_now
    depth = max(sp.z, 0.0) if use_pos else None
    if use_pos and not use_vel:
        return Command(heading=heading, speed=0.0, depth=depth, station=(sp.x, sp.y))
    return Command(heading=heading, speed=speed, depth=depth)
