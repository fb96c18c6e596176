"""Opening a MAVLink vehicle for a mission: heartbeat, telemetry rates, the rangefinder check against the mission,
the origin check, GUIDED and arming, each acknowledgement checked (MAV_CMD_SET_MESSAGE_INTERVAL,
MAV_CMD_DO_SET_MODE with MAV_MODE_FLAG_CUSTOM_MODE_ENABLED and ArduSub's custom_mode, MAV_CMD_COMPONENT_ARM_DISARM;
MAVLink common set). Anything refused or missing is a one-line `VehicleError`.
"""

from __future__ import annotations

import math
import time
from pathlib import Path

from mission.errors import VehicleError
from mission.language.models import Mission
from mission.vehicles import VehicleOptions
from mission.vehicles import ardusub as sub
from mission.vehicles.mavlink_link import MavlinkLink

MAV_CMD_SET_MESSAGE_INTERVAL = 511
MAV_CMD_DO_SET_MODE = 176
MAV_CMD_COMPONENT_ARM_DISARM = 400
MAV_MODE_FLAG_CUSTOM_MODE_ENABLED = 1
EARTH_RADIUS_M = 6371008.8
ORIGIN_TOLERANCE_M = 10.0

# message id, name, needed (a refusal of a needed one is fatal), period in control periods (0: once a second)
TELEMETRY = (
    (32, "LOCAL_POSITION_NED", True, 1), (30, "ATTITUDE", True, 1), (132, "DISTANCE_SENSOR", False, 1),
    (64, "LOCAL_POSITION_NED_COV", False, 1), (33, "GLOBAL_POSITION_INT", False, 0),
    (147, "BATTERY_STATUS", False, 0), (1, "SYS_STATUS", False, 0), (173, "RANGEFINDER", False, 1),
)


def _result_name(link: MavlinkLink, result: int | None) -> str:
    if result is None:
        return "no acknowledgement"
    entry = link.mu.mavlink.enums["MAV_RESULT"].get(result)
    return entry.name if entry is not None else f"MAV_RESULT {result}"


def altitude_elements(mission: Mission) -> list[tuple[int, str, str]]:
    """(index, id, kind) of the route elements that hold an altitude above the seabed."""
    return [(i, e.id, e.kind) for i, e in enumerate(mission.route)
            if getattr(e.params, "altitude", None) is not None]


def _located(mission: Mission, index: int, kind: str) -> str:
    """`file:line:col` of a route element's altitude (of the element when the altitude is a default)."""
    if mission.source is None:
        return f"route[{index}]"
    try:
        from mission.language.source import read_yaml

        doc = read_yaml(Path(mission.source))
        line, col = doc.where(("route", index, kind, "altitude"))
    except Exception:  # the file moved or broke since loading: say which element, without a position
        return f"{mission.source}: route[{index}]"
    return f"{mission.source}:{line}:{col}"


def _has_rangefinder(link: MavlinkLink) -> bool:
    ds = link.latest("DISTANCE_SENSOR")
    return (ds is not None and ds.orientation == 25) or link.latest("RANGEFINDER") is not None


def _check_origin(link: MavlinkLink, mission: Mission, options: VehicleOptions, wait: float) -> None:
    """Log `vehicle_origin_mismatch` when the vehicle's EKF origin (global position minus local position) is
    more than ORIGIN_TOLERANCE_M from the mission's `origin`."""
    if mission.origin is None or not link.wait_for(lambda lk: lk.latest("GLOBAL_POSITION_INT") is not None, wait):
        return  # without an origin there is nothing to compare the vehicle's with
    gp, lp = link.latest("GLOBAL_POSITION_INT"), link.latest("LOCAL_POSITION_NED")
    lat0 = mission.origin.lat
    north = math.radians(gp.lat / 1e7 - lat0) * EARTH_RADIUS_M
    east = math.radians(gp.lon / 1e7 - mission.origin.lon) * EARTH_RADIUS_M * math.cos(math.radians(lat0))
    off = math.hypot(north - lp.x, east - lp.y)
    if off > ORIGIN_TOLERANCE_M:
        options.emit("vehicle_origin_mismatch", lp.time_boot_ms / 1000.0, offset_m=off,
                     reason="the vehicle's local frame is not centred on the mission's origin")


def _require(link: MavlinkLink, what: str, command: int, params: tuple[float, ...]) -> None:
    result = link.command(command, params, timeout=3.0)
    if result != 0:
        raise VehicleError(f"the vehicle at {link.address} refused {what} ({_result_name(link, result)})")


def handshake(link: MavlinkLink, mission: Mission, options: VehicleOptions, control_period: float) -> None:
    """Everything `open_vehicle` does on the link before the executive's first tick (see the module docstring)."""
    timeout = options.connect_timeout
    deadline = time.monotonic() + timeout
    if not link.wait_for(lambda lk: lk.last_heartbeat > 0, timeout):
        raise VehicleError(f"no heartbeat from {link.address} within {timeout:g} s")
    t0 = 0.0
    for msg_id, name, needed, periods in TELEMETRY:
        interval_us = control_period * periods * 1e6 if periods else 1e6
        result = link.command(MAV_CMD_SET_MESSAGE_INTERVAL, (float(msg_id), interval_us), timeout=1.5)
        if result != 0 and needed:
            raise VehicleError(f"the vehicle at {link.address} refused to stream {name} "
                               f"({_result_name(link, result)})")
        if result != 0:
            options.emit("vehicle_command_refused", t0, command=f"SET_MESSAGE_INTERVAL {name}",
                         result=result)
    left = max(deadline - time.monotonic(), 0.5)
    if not link.wait_for(lambda lk: lk.latest("LOCAL_POSITION_NED") is not None, left):
        raise VehicleError(f"no LOCAL_POSITION_NED from {link.address} within {timeout:g} s")
    needing = altitude_elements(mission)
    if needing:
        left = max(deadline - time.monotonic(), 0.5)
        if not link.wait_for(_has_rangefinder, left):
            index, ident, kind = needing[0]
            raise VehicleError(
                f"{_located(mission, index, kind)}: {kind} '{ident}' holds an altitude, but the vehicle at "
                f"{link.address} reported no downward rangefinder (DISTANCE_SENSOR or RANGEFINDER) within "
                f"{timeout:g} s; ArduSub follows altitude in GUIDED only through depth setpoints from one")
    _check_origin(link, mission, options, min(max(deadline - time.monotonic(), 0.0), 1.5))
    _require(link, "GUIDED mode", MAV_CMD_DO_SET_MODE, (float(MAV_MODE_FLAG_CUSTOM_MODE_ENABLED), float(sub.GUIDED)))
    if not link.wait_for(lambda lk: lk.custom_mode == sub.GUIDED, 3.0):
        raise VehicleError(f"the vehicle at {link.address} acknowledged GUIDED but reports "
                           f"{sub.mode_name(link.custom_mode or 0)}")
    _require(link, "arming", MAV_CMD_COMPONENT_ARM_DISARM, (1.0,))
    if not link.wait_for(lambda lk: lk.armed, 3.0):
        raise VehicleError(f"the vehicle at {link.address} acknowledged arming but reports itself disarmed")
