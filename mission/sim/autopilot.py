"""The simulated vehicle's autopilot as MAVLink sees it: ArduSub's modes, arming, GUIDED setpoints, message
intervals, EKF source sets, the GCS failsafe, and the telemetry it streams. `mission.sim.serve` moves messages
between this and the links; the simulated truth never leaves this side.

Behaviour read from ArduPilot (not copied): `ArduSub/GCS_MAVLink_Sub.cpp` (SET_POSITION_TARGET_LOCAL_NED only in
GUIDED; heartbeat with MAV_TYPE_SUBMARINE, custom_mode = the mode number, the armed flag), `ArduSub/mode_guided.cpp`
(a velocity setpoint times out after 3 s without updates), `ArduSub/failsafe.cpp` and `ArduSub/Parameters.cpp`
(GCS failsafe: no heartbeat from the GCS system id for FS_GCS_TIMEOUT, default 5 s, while armed and after a GCS
was seen once → the FS_GCS_ENABLE action, default 2 = disarm), `libraries/GCS_MAVLink` (COMMAND_ACK for
COMMAND_LONG and for SET_MODE, MAV_CMD_SET_MESSAGE_INTERVAL). ArduSub boots disarmed in MANUAL.

Outside GUIDED (a pilot's mode), or disarmed, the simulated vehicle holds (`SimAutopilot._hold`). GCS heartbeats
are timed on the wall clock, as a GCS sends them.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

from mission.sim.mission_protocol import MissionStore
from mission.sim.vehicle import DEPTH_SIGMA_M, SimulatedVehicle
from mission.vehicle import Command
from mission.vehicles import ardusub as sub

FS_GCS_TIMEOUT = 5.0  # s, ArduSub's default
VELOCITY_TIMEOUT = 3.0  # s of vehicle time (ArduSub GUIDED_VEL_TIMEOUT_MS)
EARTH_RADIUS_M = 6371008.8

ACCEPTED, DENIED, UNSUPPORTED, FAILED = 0, 2, 3, 4
CMD_SET_MESSAGE_INTERVAL, CMD_DO_SET_MODE, CMD_ARM_DISARM, CMD_SET_EKF_SOURCE_SET = 511, 176, 400, 42007
MSG_SET_MODE = 11

# message id → default period (s of vehicle time); MAV_CMD_SET_MESSAGE_INTERVAL changes them
TELEMETRY_DEFAULTS: dict[int, float] = {
    32: 0.2, 30: 0.2, 132: 0.2, 64: 0.2, 33: 1.0, 147: 1.0, 1: 1.0, 173: 0.2,
}


class SimAutopilot:
    """ArduSub's side of the link around a `SimulatedVehicle`. `send(name, *args)` sends to every link;
    `log(event, **fields)` records what the autopilot did (mode changes, arming, failsafes)."""

    def __init__(self, vehicle: SimulatedVehicle, origin: tuple[float, float], send: Callable[..., None],
                 log: Callable[..., None], gcs_system: int = 255, gcs_timeout: float = FS_GCS_TIMEOUT):
        self.vehicle = vehicle
        self.origin = origin
        self.send = send
        self.log = log
        self.gcs_system = gcs_system
        self.gcs_timeout = gcs_timeout
        self.mode = sub.MANUAL
        self.armed = False
        self.gcs_seen = 0.0  # wall time of the GCS's last heartbeat (0: never)
        self.gcs_failsafe = False
        self.periods = dict(TELEMETRY_DEFAULTS)
        self.next_due = dict.fromkeys(self.periods, 0.0)
        self.velocity_setpoint_at: float | None = None  # vehicle time of the last velocity setpoint
        self.last_depth = vehicle.depth_meas
        self.missions = MissionStore(log)
        self._hold()

    @property
    def time_ms(self) -> int:
        return int(round(self.vehicle.truth.time * 1000.0)) & 0xFFFFFFFF

    # -- state changes -------------------------------------------------------------------------------------
    def _hold(self) -> None:
        """What the vehicle does without GUIDED setpoints: POSHOLD keeps the estimated position where it was
        entered; SURFACE rises; any other mode, or disarmed, stops the thrusters' forward work and keeps depth
        (the current then carries the vehicle, as it would a pilot's idle ROV)."""
        v = self.vehicle
        if self.armed and self.mode == sub.POSHOLD:
            command = Command(heading=v.heading_meas, speed=0.0, depth=v.depth_meas,
                              station=(v.filter.north, v.filter.east))
        else:
            depth = 0.0 if self.mode == sub.SURFACE and self.armed else v.depth_meas
            command = Command(heading=v.heading_meas, speed=0.0, depth=depth)
        v.apply(command)
        self.velocity_setpoint_at = None

    def set_mode(self, mode: int, reason: str) -> bool:
        if mode not in sub.MODES:
            return False
        if mode != self.mode:
            self.log("mode_changed", mode=sub.mode_name(mode), previous=sub.mode_name(self.mode), reason=reason)
        self.mode = mode
        if mode != sub.GUIDED:
            self._hold()
        self.heartbeat()
        return True

    def set_armed(self, armed: bool, reason: str) -> None:
        if armed != self.armed:
            self.log("armed" if armed else "disarmed", reason=reason)
        self.armed = armed
        if not armed or self.mode != sub.GUIDED:
            self._hold()
        self.heartbeat()

    # -- incoming ------------------------------------------------------------------------------------------
    def handle(self, msg: Any, reply: Callable[..., None]) -> None:
        """One message from a link; `reply(name, *args)` answers on that link only."""
        kind = msg.get_type()
        if kind.startswith("MISSION_") and self.missions.handle(msg, reply):
            return
        if kind == "HEARTBEAT":
            if msg.get_srcSystem() == self.gcs_system and msg.type == 6:  # MAV_TYPE_GCS
                self.gcs_seen = time.monotonic()
                if self.gcs_failsafe:
                    self.gcs_failsafe = False
                    self.log("gcs_failsafe_cleared")
        elif kind == "COMMAND_LONG":
            result = self._command(int(msg.command), msg)
            reply("command_ack", int(msg.command), result, 0, 0, msg.get_srcSystem(), msg.get_srcComponent())
        elif kind == "SET_MODE":
            ok = self.set_mode(int(msg.custom_mode), "SET_MODE")
            reply("command_ack", MSG_SET_MODE, ACCEPTED if ok else DENIED, 0, 0, msg.get_srcSystem(),
                  msg.get_srcComponent())
        elif kind == "SET_POSITION_TARGET_LOCAL_NED":
            self._setpoint(msg)

    def _command(self, command: int, msg: Any) -> int:
        if command == CMD_SET_MESSAGE_INTERVAL:
            msg_id, interval_us = int(msg.param1), msg.param2
            if msg_id not in TELEMETRY_DEFAULTS:
                return UNSUPPORTED
            self.periods[msg_id] = (TELEMETRY_DEFAULTS[msg_id] if interval_us == 0
                                    else math.inf if interval_us < 0 else interval_us / 1e6)
            self.next_due[msg_id] = 0.0
            return ACCEPTED
        if command == CMD_DO_SET_MODE:
            return ACCEPTED if int(msg.param1) & 1 and self.set_mode(int(msg.param2), "DO_SET_MODE") else DENIED
        if command == CMD_ARM_DISARM:
            if msg.param1 not in (0.0, 1.0):
                return UNSUPPORTED
            self.set_armed(msg.param1 == 1.0, "ARM_DISARM")
            return ACCEPTED
        if command == CMD_SET_EKF_SOURCE_SET:
            source_set = int(msg.param1)
            if source_set not in (sub.SOURCE_SET_ACOUSTIC, sub.SOURCE_SET_DEAD_RECKONING):
                return DENIED
            self.vehicle.set_aiding(source_set == sub.SOURCE_SET_ACOUSTIC)
            self.log("ekf_source_set", source_set=source_set)
            return ACCEPTED
        return UNSUPPORTED

    def _setpoint(self, msg: Any) -> None:
        if self.mode != sub.GUIDED or not self.armed or msg.coordinate_frame != sub.MAV_FRAME_LOCAL_NED:
            return  # ArduSub ignores setpoints outside GUIDED; the body frames are not served here
        sp = sub.Setpoint(int(msg.type_mask), msg.x, msg.y, msg.z, msg.vx, msg.vy, msg.vz, msg.yaw)
        command = sub.command_from_setpoint(sp, self.vehicle.heading_meas)
        if command is None:
            return
        self.vehicle.apply(command)
        self.velocity_setpoint_at = self.vehicle.truth.time if not sp.type_mask & sub.VELOCITY else None

    # -- every step ----------------------------------------------------------------------------------------
    def check(self) -> None:
        """Timeouts after a simulation step: the GUIDED velocity timeout and the GCS failsafe."""
        t = self.vehicle.truth.time
        if self.velocity_setpoint_at is not None and t - self.velocity_setpoint_at > VELOCITY_TIMEOUT:
            self._hold()
        if self.gcs_seen and not self.gcs_failsafe and self.armed \
                and time.monotonic() - self.gcs_seen > self.gcs_timeout:
            self.gcs_failsafe = True
            self.log("gcs_failsafe", action="disarm", silent_s=round(time.monotonic() - self.gcs_seen, 2))
            self.set_armed(False, "GCS failsafe (FS_GCS_ENABLE 2: disarm)")

    def heartbeat(self) -> None:
        base = 1 | 16 | 64  # CUSTOM_MODE_ENABLED | STABILIZE_ENABLED | MANUAL_INPUT_ENABLED
        if self.mode in (sub.GUIDED, 3, 7, sub.POSHOLD):  # AUTO, CIRCLE: ArduSub flags these as guided too
            base |= 8
        if self.armed:
            base |= 128
        status = 5 if self.gcs_failsafe else 4 if self.armed else 3  # CRITICAL, ACTIVE, STANDBY
        self.send("heartbeat", 12, 3, base, self.mode, status)  # MAV_TYPE_SUBMARINE, MAV_AUTOPILOT_ARDUPILOTMEGA

    def telemetry(self, dt: float) -> None:
        """Send the messages whose period has come round by the vehicle's clock."""
        t = self.vehicle.truth.time
        for msg_id, period in self.periods.items():
            if math.isfinite(period) and t + 1e-6 >= self.next_due[msg_id]:
                self.next_due[msg_id] = max(self.next_due[msg_id] + period, t + period - 0.5 * dt)
                self._send_message(msg_id, dt)
        self.last_depth = self.vehicle.depth_meas

    def _send_message(self, msg_id: int, dt: float) -> None:
        v, f, ms = self.vehicle, self.vehicle.filter, self.time_ms
        h = math.radians(v.heading_meas)
        vn, ve = v.truth.speed * math.cos(h), v.truth.speed * math.sin(h)  # speed the vehicle knows, its heading
        vd = (v.depth_meas - self.last_depth) / dt if dt > 0 else 0.0
        if msg_id == 32:
            self.send("local_position_ned", ms, f.north, f.east, v.depth_meas, vn, ve, vd)
        elif msg_id == 30:
            self.send("attitude", ms, 0.0, 0.0, sub.heading_to_yaw(v.heading_meas), 0.0, 0.0, 0.0)
        elif msg_id == 33:
            lat0, lon0 = self.origin
            lat = lat0 + math.degrees(f.north / EARTH_RADIUS_M)
            lon = lon0 + math.degrees(f.east / (EARTH_RADIUS_M * math.cos(math.radians(lat0))))
            self.send("global_position_int", ms, int(lat * 1e7), int(lon * 1e7), int(-v.depth_meas * 1000),
                      int(-v.depth_meas * 1000), int(vn * 100), int(ve * 100), int(vd * 100),
                      int(v.heading_meas * 100) % 36000)
        elif msg_id == 132:
            alt = v.altitude_meas
            top = int(min(v.dvl_max_altitude * 100, 65000))
            reading, quality = (int(alt * 100), 100) if alt is not None else (top + 1, 1)  # 1: invalid signal
            self.send("distance_sensor", ms, 10, top, reading, 1, 0, 25, 255, 0.0, 0.0, (0, 0, 0, 0), quality)
        elif msg_id == 173:
            if v.altitude_meas is not None:  # ArduSub sends RANGEFINDER only while it has a reading
                self.send("rangefinder", v.altitude_meas, 0.0)
        elif msg_id == 64:
            cov = [0.0] * 45
            cov[0] = cov[9] = f.var
            cov[17] = DEPTH_SIGMA_M**2
            self.send("local_position_ned_cov", ms * 1000, 0, f.north, f.east, v.depth_meas, vn, ve, vd, 0.0, 0.0,
                      0.0, cov)
        elif msg_id in (147, 1):
            capacity = v.mission.vehicle.energy_wh
            remaining = int(max(0.0, min(100.0, 100.0 * (1.0 - v.energy_used_wh / capacity))))
            if msg_id == 147:
                self.send("battery_status", 0, 0, 0, 32767, [16000] + [65535] * 9, -1, -1,
                          int(v.energy_used_wh * 36.0), remaining)
            else:
                self.send("sys_status", 0, 0, 0, 0, 16000, -1, remaining, 0, 0, 0, 0, 0, 0)
