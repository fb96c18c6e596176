"""A MAVLink link to one vehicle, seen from the ground/onboard-computer side: a pymavlink connection, a receiver
thread that keeps the latest message of each type under a lock, a heartbeat thread (1 Hz, never the control
loop), and commands sent with their COMMAND_ACK awaited.

We send heartbeats as a GCS (MAV_TYPE_GCS, system id 255 by default): ArduSub's GCS failsafe watches the
heartbeats of its configured GCS system id (MAV_GCS_SYSID, formerly SYSID_MYGCS, default 255;
`ArduSub/failsafe.cpp`), so the executive's link is the one whose loss the autopilot acts on.
"""

from __future__ import annotations

import os
import threading
import time
from typing import Any

from mission.errors import VehicleError

GCS_SYSTEM_ID = 255
MAV_COMP_ID_MISSIONPLANNER = 190


def mavutil() -> Any:
    """pymavlink's `mavutil`, speaking MAVLink 2 (ArduSub does; message ids above 255 need it)."""
    os.environ.setdefault("MAVLINK20", "1")
    try:
        from pymavlink import mavutil as mu
    except ImportError as exc:  # an onboard extra: say how to get it
        raise VehicleError("the MAVLink adapter needs pymavlink: pip install pymavlink") from exc
    return mu


def connect(address: str, source_system: int, source_component: int) -> Any:
    """Open a pymavlink connection; any failure (bad address, port in use, no such device) is a VehicleError."""
    mu = mavutil()
    try:
        return mu.mavlink_connection(address, source_system=source_system, source_component=source_component,
                                     autoreconnect=False, force_connected=False, retries=0)
    except Exception as exc:  # pymavlink raises OSError, ValueError, serial errors, … for bad addresses
        raise VehicleError(f"cannot open MAVLink address '{address}': {exc}") from exc


class MavlinkLink:
    """The link to the first non-GCS system that sends us a heartbeat (the vehicle)."""

    def __init__(self, address: str, source_system: int = GCS_SYSTEM_ID,
                 source_component: int = MAV_COMP_ID_MISSIONPLANNER):
        self.address = address
        self.mu = mavutil()
        self.conn = connect(address, source_system, source_component)
        self.mav = self.conn.mav
        self._lock = threading.Condition()
        self._send_lock = threading.Lock()
        self._latest: dict[str, Any] = {}
        self._received: dict[str, float] = {}
        self._acks: dict[int, Any] = {}
        self.target_system = 0
        self.target_component = 0
        self.last_heartbeat = 0.0  # host monotonic time of the vehicle's last heartbeat (0: never)
        self.custom_mode: int | None = None
        self.armed = False
        self.messages = 0
        self._stop = threading.Event()
        self._threads = [threading.Thread(target=self._receive, name="mavlink-rx", daemon=True),
                         threading.Thread(target=self._beat, name="mavlink-heartbeat", daemon=True)]
        for t in self._threads:
            t.start()

    # -- threads -----------------------------------------------------------------------------------------------
    def _beat(self) -> None:
        while not self._stop.is_set():
            try:
                with self._send_lock:
                    self.mav.heartbeat_send(self.mu.mavlink.MAV_TYPE_GCS, self.mu.mavlink.MAV_AUTOPILOT_INVALID,
                                            0, 0, self.mu.mavlink.MAV_STATE_ACTIVE)
            except OSError:
                pass  # the far end is not there (yet): link loss is decided from its heartbeats, not ours
            self._stop.wait(1.0)

    def _receive(self) -> None:
        mav = self.mu.mavlink
        while not self._stop.is_set():
            try:
                msg = self.conn.recv_match(blocking=True, timeout=0.1)
            except (OSError, ValueError):
                if self._stop.is_set():
                    return
                time.sleep(0.05)
                continue
            if msg is None:
                continue
            kind = msg.get_type()
            if kind == "BAD_DATA":
                continue
            src = msg.get_srcSystem()
            with self._lock:
                if kind == "HEARTBEAT":
                    if msg.type == mav.MAV_TYPE_GCS or msg.autopilot == mav.MAV_AUTOPILOT_INVALID:
                        continue  # another GCS or a companion, not the vehicle
                    if self.target_system == 0:
                        self.target_system, self.target_component = src, msg.get_srcComponent()
                    if src != self.target_system:
                        continue
                    self.last_heartbeat = time.monotonic()
                    self.custom_mode = int(msg.custom_mode)
                    self.armed = bool(msg.base_mode & mav.MAV_MODE_FLAG_SAFETY_ARMED)
                elif self.target_system and src != self.target_system:
                    continue
                if kind == "COMMAND_ACK":
                    self._acks[int(msg.command)] = msg
                self._latest[kind] = msg
                self._received[kind] = time.monotonic()
                self.messages += 1
                self._lock.notify_all()

    # -- reading -----------------------------------------------------------------------------------------------
    def latest(self, kind: str) -> Any:
        """The newest message of this type from the vehicle (None if none has come)."""
        with self._lock:
            return self._latest.get(kind)

    def wait_for(self, predicate: Any, timeout: float) -> bool:
        """Block until `predicate(self)` holds (checked on each message received) or the timeout passes."""
        deadline = time.monotonic() + timeout
        with self._lock:
            while not predicate(self):
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                self._lock.wait(min(left, 0.1))
            return True

    def age(self, kind: str) -> float:
        """Host seconds since the newest message of this type arrived (inf if none has)."""
        with self._lock:
            got = self._received.get(kind)
            return time.monotonic() - got if got is not None else float("inf")

    def silence(self) -> float:
        """Seconds since the vehicle's last heartbeat (inf before the first)."""
        with self._lock:
            return time.monotonic() - self.last_heartbeat if self.last_heartbeat else float("inf")

    # -- sending -----------------------------------------------------------------------------------------------
    def send(self, name: str, *args: Any) -> None:
        """Send one message by its pymavlink name (`set_position_target_local_ned`, …) to the far end."""
        with self._send_lock:
            getattr(self.mav, f"{name}_send")(*args)

    def send_command(self, command: int, params: tuple[float, ...], confirmation: int = 0) -> None:
        """Send COMMAND_LONG without waiting (its acknowledgement: `take_ack`); an older ack of it is dropped."""
        p = tuple(params) + (0.0,) * (7 - len(params))
        with self._lock:
            self._acks.pop(command, None)
        self.send("command_long", self.target_system, self.target_component, command, confirmation, *p)

    def take_ack(self, command: int) -> int | None:
        """The MAV_RESULT of the command's COMMAND_ACK if one has come (and forget it), else None."""
        with self._lock:
            ack = self._acks.pop(command, None)
        return None if ack is None else int(ack.result)

    def command(self, command: int, params: tuple[float, ...], timeout: float = 2.0, tries: int = 3) -> int | None:
        """Send COMMAND_LONG and return the MAV_RESULT of its COMMAND_ACK (None: no acknowledgement). Resent
        (with the confirmation counter raised) when no acknowledgement comes within timeout / tries."""
        for confirmation in range(tries):
            self.send_command(command, params, confirmation)
            if self.wait_for(lambda link: command in link._acks, timeout / tries):
                return self.take_ack(command)
        return None

    def close(self) -> None:
        self._stop.set()
        for t in self._threads:
            t.join(timeout=2.0)
        try:
            self.conn.close()
        except OSError:
            pass
