"""The MAVLink mission protocol on `auv sim serve`'s side, as ArduSub answers it: a ground station uploads a
mission (MISSION_COUNT, then MISSION_REQUEST_INT for each item, MISSION_ITEM_INT back, MISSION_ACK at the end)
and reads it back (MISSION_REQUEST_LIST, MISSION_COUNT, MISSION_REQUEST_INT, MISSION_ITEM_INT). The mission is
stored and logged (`mission_uploaded`), as the autopilot would store it for AUTO mode; the simulator does not fly
AUTO missions (`auv run` flies in GUIDED). Items with a command or frame ArduSub does not take for a sub are
refused with MAV_MISSION_UNSUPPORTED / MAV_MISSION_UNSUPPORTED_FRAME, and an upload that stops is abandoned when
the next MISSION_COUNT comes.

Replies go through `reply(name, *args)` (the pymavlink `<name>_send` of the link the request came on).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

MAV_MISSION_TYPE_MISSION = 0
MAV_MISSION_ACCEPTED, MAV_MISSION_UNSUPPORTED_FRAME, MAV_MISSION_UNSUPPORTED = 0, 3, 4
MAV_MISSION_INVALID_SEQUENCE = 13
# Commands ArduSub's mission takes: navigation (waypoint, loiters, RTL, land, spline waypoint, guided enable,
# delay), conditions (delay, distance, yaw) and do-commands (jump, change speed, set home, relay, servo, ROI,
# camera trigger distance, digicam control, mount).
NAV_COMMANDS = {16, 17, 18, 19, 20, 21, 82, 92, 93, 112, 114, 115, 177, 178, 179, 181, 183, 201, 203, 205, 206}
# global, mission (do-commands), relative-alt, global_int, relative-alt_int, terrain-alt, terrain-alt_int
FRAMES = {0, 2, 3, 5, 6, 10, 11}


@dataclass(frozen=True)
class StoredItem:
    seq: int
    frame: int
    command: int
    params: tuple[float, float, float, float]
    x: int  # latitude, degrees × 1e7
    y: int  # longitude, degrees × 1e7
    z: float
    autocontinue: int


class MissionStore:
    """The vehicle's stored mission and an upload under way."""

    def __init__(self, log: Callable[..., None]):
        self.log = log
        self.items: list[StoredItem] = []
        self._incoming: list[StoredItem] | None = None
        self._count = 0

    def handle(self, msg: Any, reply: Callable[..., None]) -> bool:
        """Act on a mission-protocol message; False when `msg` is not one."""
        kind = msg.get_type()
        src = (msg.get_srcSystem(), msg.get_srcComponent())
        if kind == "MISSION_COUNT":
            self._count, self._incoming = int(msg.count), []
            if self._count == 0:
                self._finish(reply, src)
            else:
                reply("mission_request_int", *src, 0, MAV_MISSION_TYPE_MISSION)
        elif kind == "MISSION_ITEM_INT" and self._incoming is not None:
            self._item(msg, reply, src)
        elif kind == "MISSION_REQUEST_LIST":
            reply("mission_count", *src, len(self.items), MAV_MISSION_TYPE_MISSION)
        elif kind in ("MISSION_REQUEST_INT", "MISSION_REQUEST") and 0 <= int(msg.seq) < len(self.items):
            it = self.items[int(msg.seq)]
            reply("mission_item_int", *src, it.seq, it.frame, it.command, 0, it.autocontinue, *it.params, it.x,
                  it.y, it.z, MAV_MISSION_TYPE_MISSION)
        elif kind == "MISSION_ACK":
            pass  # the end of a download
        else:
            return False
        return True

    def _item(self, msg: Any, reply: Callable[..., None], src: tuple[int, int]) -> None:
        assert self._incoming is not None
        seq = int(msg.seq)
        if seq != len(self._incoming):
            reply("mission_ack", *src, MAV_MISSION_INVALID_SEQUENCE, MAV_MISSION_TYPE_MISSION)
            self._incoming = None
            return
        if int(msg.command) not in NAV_COMMANDS or int(msg.frame) not in FRAMES:
            unsupported = MAV_MISSION_UNSUPPORTED if int(msg.command) not in NAV_COMMANDS else \
                MAV_MISSION_UNSUPPORTED_FRAME
            self.log("mission_refused", item=seq, command=int(msg.command), frame=int(msg.frame))
            reply("mission_ack", *src, unsupported, MAV_MISSION_TYPE_MISSION)
            self._incoming = None
            return
        self._incoming.append(StoredItem(seq, int(msg.frame), int(msg.command),
                                         (float(msg.param1), float(msg.param2), float(msg.param3),
                                          float(msg.param4)), int(msg.x), int(msg.y), float(msg.z),
                                         int(msg.autocontinue)))
        if len(self._incoming) < self._count:
            reply("mission_request_int", *src, len(self._incoming), MAV_MISSION_TYPE_MISSION)
        else:
            self._finish(reply, src)

    def _finish(self, reply: Callable[..., None], src: tuple[int, int]) -> None:
        self.items, self._incoming = list(self._incoming or []), None
        self.log("mission_uploaded", items=len(self.items),
                 waypoints=[[it.x / 1e7, it.y / 1e7, it.z] for it in self.items])
        reply("mission_ack", *src, MAV_MISSION_ACCEPTED, MAV_MISSION_TYPE_MISSION)
