"""MAVLink missions of the plannable route (`mission.export.plan`): QGC WPL 110 plain text, as QGroundControl,
Mission Planner and pymavlink's `mavwp` read it, and an upload over MAVLink's mission protocol
(MISSION_COUNT, MISSION_REQUEST_INT, MISSION_ITEM_INT, MISSION_ACK) to any endpoint pymavlink reaches.

Item 0 is home (MAV_FRAME_GLOBAL). Each leg starts with MAV_CMD_DO_CHANGE_SPEED (ground speed, m/s) and goes on
with MAV_CMD_NAV_WAYPOINT items: a leg at a depth uses MAV_FRAME_GLOBAL_RELATIVE_ALT with z = −depth (ArduSub
measures altitude from the surface, positive up); a leg at an altitude above the seabed uses
MAV_FRAME_GLOBAL_TERRAIN_ALT with z = altitude, which an autopilot flies from its rangefinder (ArduSub's surface
tracking) or refuses at upload. Latitudes and longitudes are written with 9 decimals (0.1 mm).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from mission.errors import AuvError
from mission.export.plan import Leg
from mission.geodesy import ned_to_geodetic

MAV_FRAME_GLOBAL = 0
MAV_FRAME_MISSION = 2
MAV_FRAME_GLOBAL_RELATIVE_ALT = 3
MAV_FRAME_GLOBAL_TERRAIN_ALT = 10
MAV_CMD_NAV_WAYPOINT = 16
MAV_CMD_DO_CHANGE_SPEED = 178
SPEED_TYPE_GROUND = 1.0
WPL_HEADER = "QGC WPL 110"
ACCEPTANCE_RADIUS_M = 2.0  # survey waypoints; a transit's target uses its element's capture radius when given


class MissionUploadError(AuvError):
    """A mission upload over MAVLink's mission protocol was not acknowledged as accepted."""


@dataclass(frozen=True)
class MissionItem:
    """One MAVLink mission item (the fields of MISSION_ITEM_INT, with lat/lon in degrees)."""

    seq: int
    frame: int
    command: int
    params: tuple[float, float, float, float]
    lat: float
    lon: float
    z: float
    current: int = 0
    autocontinue: int = 1


def mission_items(legs: Sequence[Leg], lat0: float, lon0: float, home_ne: tuple[float, float] = (0.0, 0.0),
                  capture_radius: dict[str, float] | None = None) -> list[MissionItem]:
    """The items of a plan: home, then for each leg a speed change and its waypoints."""
    radius = capture_radius or {}
    hlat, hlon = ned_to_geodetic(home_ne[0], home_ne[1], lat0, lon0)
    items = [MissionItem(0, MAV_FRAME_GLOBAL, MAV_CMD_NAV_WAYPOINT, (0.0, 0.0, 0.0, 0.0), float(hlat), float(hlon),
                         0.0, current=1)]
    for leg in legs:
        items.append(MissionItem(len(items), MAV_FRAME_MISSION, MAV_CMD_DO_CHANGE_SPEED,
                                 (SPEED_TYPE_GROUND, leg.speed, -1.0, 0.0), 0.0, 0.0, 0.0))
        if leg.altitude is not None:
            frame, z = MAV_FRAME_GLOBAL_TERRAIN_ALT, leg.altitude
        else:
            frame, z = MAV_FRAME_GLOBAL_RELATIVE_ALT, -(leg.depth or 0.0)
        accept = radius.get(leg.element, ACCEPTANCE_RADIUS_M)
        for n, e in leg.points_ne:
            lat, lon = ned_to_geodetic(n, e, lat0, lon0)
            items.append(MissionItem(len(items), frame, MAV_CMD_NAV_WAYPOINT, (0.0, accept, 0.0, 0.0), float(lat),
                                     float(lon), float(z)))
    return items


def wpl_text(items: Sequence[MissionItem]) -> str:
    """QGC WPL 110: a header line, then one tab-separated line of 12 fields per item."""
    lines = [WPL_HEADER]
    for it in items:
        p = "\t".join(f"{v:.6f}" for v in it.params)
        lines.append(f"{it.seq}\t{it.current}\t{it.frame}\t{it.command}\t{p}\t{it.lat:.9f}\t{it.lon:.9f}\t"
                     f"{it.z:.3f}\t{it.autocontinue}")
    return "\n".join(lines) + "\n"


def write_wpl(items: Sequence[MissionItem], out: Path) -> None:
    out.write_text(wpl_text(items), encoding="utf-8")


def read_wpl(path: Path) -> list[MissionItem]:
    """The items of a QGC WPL 110 file (AuvError naming the line that is not one)."""
    lines = path.read_text(encoding="utf-8").splitlines()
    if not lines or lines[0].strip() != WPL_HEADER:
        raise AuvError(f"{path}:1: not a QGC WPL 110 file (expected the header '{WPL_HEADER}')")
    items = []
    for k, line in enumerate(lines[1:], start=2):
        f = line.split()
        if not f or line.startswith("#"):
            continue
        try:
            items.append(MissionItem(int(f[0]), int(f[2]), int(f[3]), (float(f[4]), float(f[5]), float(f[6]),
                                     float(f[7])), float(f[8]), float(f[9]), float(f[10]), int(f[1]), int(f[11])))
        except (IndexError, ValueError) as exc:
            raise AuvError(f"{path}:{k}: not a mission item of 12 fields ({exc})") from exc
    return items


def upload_mission(items: Sequence[MissionItem], address: str, *, target_system: int = 1,
                   target_component: int = 1, timeout: float = 5.0) -> None:
    """Send `items` to the vehicle at `address` (a pymavlink connection string, e.g. udpout:127.0.0.1:14550) with
    the mission protocol, answering each MISSION_REQUEST_INT (or MISSION_REQUEST) until MISSION_ACK.

    Raises MissionUploadError when the vehicle does not answer within `timeout` seconds of the last message, or
    acknowledges with anything but MAV_MISSION_ACCEPTED.
    """
    from mission.vehicles.mavlink_link import mavutil  # MAVLink 2, as the adapter speaks it

    link = mavutil().mavlink_connection(address, source_system=255, source_component=190)
    mav = mavutil().mavlink
    try:
        deadline = time.monotonic() + timeout
        last_count: float | None = None
        requested = False
        while True:
            now = time.monotonic()
            if now > deadline:
                raise MissionUploadError(f"{address}: no answer to the mission upload within {timeout:g} s")
            if not requested and (last_count is None or now - last_count > 1.0):  # repeated until a request
                link.mav.mission_count_send(target_system, target_component, len(items))
                last_count = now
            msg = link.recv_match(type=["MISSION_REQUEST_INT", "MISSION_REQUEST", "MISSION_ACK"], blocking=True,
                                  timeout=0.2)
            if msg is None:
                continue
            deadline, requested = time.monotonic() + timeout, True
            if msg.get_type() == "MISSION_ACK":
                if msg.type != mav.MAV_MISSION_ACCEPTED:
                    raise MissionUploadError(f"{address}: the vehicle refused the mission (MAV_MISSION_RESULT "
                                             f"{msg.type})")
                return
            if not 0 <= msg.seq < len(items):
                raise MissionUploadError(f"{address}: the vehicle asked for item {msg.seq} of {len(items)}")
            it = items[msg.seq]
            link.mav.mission_item_int_send(target_system, target_component, it.seq, it.frame, it.command,
                                           it.current, it.autocontinue, *it.params, round(it.lat * 1e7),
                                           round(it.lon * 1e7), it.z)
    finally:
        link.close()
