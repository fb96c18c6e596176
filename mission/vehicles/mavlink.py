"""The MAVLink vehicle adapter (`auv run --vehicle mavlink:ADDRESS`) for ArduSub-class autopilots.

ADDRESS is a pymavlink connection string: `udpin:0.0.0.0:14550`, `udpout:HOST:PORT`, `tcp:HOST:PORT`,
`/dev/ttyUSB0,57600`. What it reads and sends (ArduSub sources and the MAVLink common set, see
`mission.vehicles.ardusub`):

- navigation: LOCAL_POSITION_NED (north, east, depth = z, speed over ground; its `time_boot_ms` is the mission's
  clock, never the host's), ATTITUDE (heading = yaw; GLOBAL_POSITION_INT's `hdg` when no ATTITUDE came), altitude
  from a downward DISTANCE_SENSOR (orientation MAV_SENSOR_ROTATION_PITCH_270) or ArduPilot's RANGEFINDER, energy
  from BATTERY_STATUS (`energy_consumed`, else `battery_remaining` × the mission's `vehicle.energy_wh`) or
  SYS_STATUS. The local frame is the vehicle's EKF origin, which must be the mission's `origin`: at open the
  adapter compares GLOBAL_POSITION_INT with the local position and logs `vehicle_origin_mismatch` beyond 10 m.
- `position_sigma`: from LOCAL_POSITION_NED_COV (√ of the mean horizontal variance) when the vehicle sends it.
  ArduPilot's EKF_STATUS_REPORT carries normalised innovation test ratios, not metres (`NavEKF3_core` fills
  `pos_horiz_variance` with √posTestRatio), so it cannot be a sigma; without a covariance message the mission's
  USBL sigma (1 m without USBL) stands in.
- commands: SET_POSITION_TARGET_LOCAL_NED in MAV_FRAME_LOCAL_NED every control tick (`ardusub.setpoint_for`),
  altitude mapped onto depth from the latest rangefinder reading; nothing is sent while a pilot has the vehicle.
- a pilot taking over: any mode other than GUIDED (or a disarm) that we did not ask for gives `in_control False`
  and a `vehicle_mode_changed` event; GUIDED again (armed) hands the mission back.
- aiding: MAV_CMD_SET_EKF_SOURCE_SET, source set 1 = acoustic fixes, 2 = dead reckoning; its COMMAND_ACK is
  checked on later ticks (never blocking control) and a refusal is a `vehicle_command_refused` event.
- link loss: the vehicle's heartbeat silent for `safety.link_timeout` → `LinkLostError` from `observe`/`advance`.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

from mission.errors import LinkLostError, VehicleError
from mission.language.models import Mission
from mission.vehicle import Command, NavState, Observation
from mission.vehicles import VehicleOptions
from mission.vehicles import ardusub as sub
from mission.vehicles.mavlink_link import MavlinkLink
from mission.vehicles.mavlink_open import handshake

CONTROL_PERIOD = 0.2  # s of vehicle time per control tick (the simulator's step)
ADVANCE_WALL_LIMIT = 1.0  # s: `advance` never waits longer for the vehicle's clock
ACK_TIMEOUT = 3.0  # s: a command without acknowledgement by then is logged as unacknowledged
RANGE_MAX_AGE = 1.0  # s of vehicle time: an older rangefinder reading is no reading
MAV_SENSOR_ROTATION_PITCH_270 = 25  # pointing down
MAV_CMD_SET_EKF_SOURCE_SET = 42007
MAV_RESULT_ACCEPTED = 0


@dataclass
class _Pending:
    command: int
    what: str
    sent: float  # host monotonic time


def _altitude(link: MavlinkLink, now_ms: int) -> float | None:
    """The latest valid downward range (m) no older than RANGE_MAX_AGE of vehicle time."""
    ds = link.latest("DISTANCE_SENSOR")
    if ds is not None and ds.orientation == MAV_SENSOR_ROTATION_PITCH_270 and ds.signal_quality != 1 \
            and ds.min_distance <= ds.current_distance <= ds.max_distance \
            and now_ms - ds.time_boot_ms <= RANGE_MAX_AGE * 1000:
        return float(ds.current_distance) / 100.0
    rf = link.latest("RANGEFINDER")  # ArduPilot's own message has no timestamp: its age is the host's
    if ds is None and rf is not None and rf.distance > 0.0 and link.age("RANGEFINDER") <= RANGE_MAX_AGE:
        return float(rf.distance)
    return None


class MavlinkVehicle:
    """`VehicleInterface` over a MAVLink link to an armed vehicle in GUIDED (see the module docstring)."""

    def __init__(self, link: MavlinkLink, mission: Mission, options: VehicleOptions,
                 control_period: float = CONTROL_PERIOD):
        self.link = link
        self.mission = mission
        self.emit = options.emit
        self.control_period = control_period
        self.link_timeout = mission.safety.link_timeout
        usbl = mission.sensors.usbl
        self.sigma_fallback = usbl.sigma if usbl is not None else 1.0
        self.nav: NavState | None = None
        self._clock: float | None = None  # vehicle time the last `advance` reached
        self.in_control = True
        self._mode_seen = (sub.GUIDED, True)
        self._pending: list[_Pending] = []
        self.aiding: bool | None = None
        self.payload: frozenset[str] = frozenset()
        self.frame_rate_hz: float | None = None
        self._payload_logged = False

    # -- reading -------------------------------------------------------------------------------------------
    def _check_link(self) -> None:
        silent = self.link.silence()
        if silent > self.link_timeout:
            raise LinkLostError(f"no heartbeat from the vehicle at {self.link.address} for {silent:.1f} s "
                                f"(link_timeout {self.link_timeout:g} s)")

    def _nav(self) -> NavState:
        link = self.link
        lp = link.latest("LOCAL_POSITION_NED")
        if lp is None:
            raise VehicleError(f"the vehicle at {link.address} sends no LOCAL_POSITION_NED")
        att = link.latest("ATTITUDE")
        gp = link.latest("GLOBAL_POSITION_INT")
        if att is not None:
            heading = sub.yaw_to_heading(att.yaw)
        elif gp is not None and gp.hdg != 65535:
            heading = gp.hdg / 100.0
        else:
            heading = self.nav.heading if self.nav is not None else 0.0
        cov = link.latest("LOCAL_POSITION_NED_COV")
        sigma = self.sigma_fallback
        if cov is not None and math.isfinite(cov.covariance[0]) and math.isfinite(cov.covariance[9]):
            sigma = math.sqrt(max(0.5 * (cov.covariance[0] + cov.covariance[9]), 0.0))
        return NavState(time=lp.time_boot_ms / 1000.0, north=lp.x, east=lp.y, depth=max(lp.z, 0.0),
                        heading=heading, speed=math.hypot(lp.vx, lp.vy),
                        altitude=_altitude(link, lp.time_boot_ms), position_sigma=sigma,
                        energy_wh=self._energy_wh())

    def _energy_wh(self) -> float:
        capacity = self.mission.vehicle.energy_wh
        bat = self.link.latest("BATTERY_STATUS")
        if bat is not None and bat.energy_consumed >= 0:
            return capacity - float(bat.energy_consumed) * 100.0 / 3600.0  # hJ → Wh
        if bat is not None and bat.battery_remaining >= 0:
            return capacity * float(bat.battery_remaining) / 100.0
        status = self.link.latest("SYS_STATUS")
        if status is not None and status.battery_remaining >= 0:
            return capacity * float(status.battery_remaining) / 100.0
        return capacity

    def _watch_mode(self, t: float) -> None:
        mode, armed = self.link.custom_mode, self.link.armed
        if mode is None or (mode, armed) == self._mode_seen:
            return
        self._mode_seen = (mode, armed)
        self.in_control = mode == sub.GUIDED and armed
        self.emit("vehicle_mode_changed", t, mode=sub.mode_name(mode), armed=armed, in_control=self.in_control)

    def _check_acks(self, t: float) -> None:
        still = []
        for p in self._pending:
            ack = self.link.take_ack(p.command)
            if ack is not None:
                if ack != MAV_RESULT_ACCEPTED:
                    self.emit("vehicle_command_refused", t, command=p.what, result=int(ack))
            elif time.monotonic() - p.sent > ACK_TIMEOUT:
                self.emit("vehicle_command_refused", t, command=p.what, result=None,
                          reason=f"no acknowledgement within {ACK_TIMEOUT:g} s")
            else:
                still.append(p)
        self._pending = still

    def observe(self) -> Observation:
        self._check_link()
        nav = self._nav()
        self.nav = nav
        self._watch_mode(nav.time)
        self._check_acks(nav.time)
        return Observation(nav, in_control=self.in_control)

    # -- commanding ----------------------------------------------------------------------------------------
    def apply(self, command: Command) -> None:
        if not self.in_control or self.nav is None:
            return  # a pilot has the vehicle (or nothing observed yet): setpoints would fight them
        nav = self.nav
        sp = sub.setpoint_for(command, nav.north, nav.east, nav.depth, nav.altitude)
        link = self.link
        link.send("set_position_target_local_ned", int(nav.time * 1000) & 0xFFFFFFFF, link.target_system,
                  link.target_component, sub.MAV_FRAME_LOCAL_NED, sp.type_mask, sp.x, sp.y, sp.z, sp.vx, sp.vy,
                  sp.vz, 0.0, 0.0, 0.0, sp.yaw, 0.0)

    def set_aiding(self, usbl: bool) -> None:
        if usbl == self.aiding:
            return
        self.aiding = usbl
        source_set = sub.SOURCE_SET_ACOUSTIC if usbl else sub.SOURCE_SET_DEAD_RECKONING
        self.link.send_command(MAV_CMD_SET_EKF_SOURCE_SET, (float(source_set),))
        self._pending.append(_Pending(MAV_CMD_SET_EKF_SOURCE_SET, f"SET_EKF_SOURCE_SET {source_set}",
                                      time.monotonic()))

    def _log_payload_once(self) -> None:
        if not self._payload_logged and (self.payload or self.frame_rate_hz is not None):
            self._payload_logged = True
            t = self.nav.time if self.nav is not None else 0.0
            self.emit("payload_not_streamed", t, sensors=sorted(self.payload), frame_rate_hz=self.frame_rate_hz,
                      reason="the MAVLink adapter carries no payload streams; sensor products stay empty")

    def set_payload(self, sensors: frozenset[str]) -> None:
        self.payload = frozenset(sensors)
        self._log_payload_once()

    def set_frame_rate(self, rate_hz: float | None) -> None:
        self.frame_rate_hz = rate_hz
        self._log_payload_once()

    def advance(self) -> None:
        """Wait until a LOCAL_POSITION_NED one control period newer than the last observed one arrives (at most
        ADVANCE_WALL_LIMIT of wall time); LinkLostError when the heartbeat has been silent too long."""
        latest = self.link.latest("LOCAL_POSITION_NED")
        now = latest.time_boot_ms / 1000.0 if latest is not None else -math.inf
        start = self._clock if self._clock is not None and self._clock <= now + 1.0 else now  # reboot: restart
        due_ms = (start + self.control_period) * 1000.0 - 1.0  # 1 ms: time_boot_ms is rounded
        deadline = time.monotonic() + ADVANCE_WALL_LIMIT

        def moved(link: MavlinkLink) -> bool:
            lp = link.latest("LOCAL_POSITION_NED")
            return (lp is not None and lp.time_boot_ms >= due_ms) or link.silence() > self.link_timeout

        while time.monotonic() < deadline:
            if self.link.wait_for(moved, min(0.1, max(deadline - time.monotonic(), 0.0))):
                break
        self._check_link()
        latest = self.link.latest("LOCAL_POSITION_NED")
        if latest is not None and latest.time_boot_ms >= due_ms:
            self._clock = start + self.control_period  # ticks stay on the period's grid

    def close(self) -> None:
        self.link.close()


def open_vehicle(address: str, mission: Mission, options: VehicleOptions) -> MavlinkVehicle:
    """The `auv.vehicles` factory: connect, wait for the heartbeat, request the telemetry, check the rangefinder
    against the mission, set GUIDED and arm (each acknowledgement checked); VehicleError otherwise."""
    link = MavlinkLink(address)
    try:
        handshake(link, mission, options, CONTROL_PERIOD)
    except BaseException:
        link.close()
        raise
    return MavlinkVehicle(link, mission, options)
