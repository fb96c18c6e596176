"""The simulated vehicle: true kinematics in a scene, sensors with their errors (DVL/INS, depth, USBL), the
onboard navigation filter, energy use, and a log of truth against estimate. Behind the `VehicleInterface` the
executive sees only the estimate.
"""

from __future__ import annotations

import functools
import math
import random
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mission.language.models import Mission
from mission.navigation import NavigationFilter
from mission.plugin_api import StereoImages
from mission.runfolder import TRAJECTORY_COLUMNS as TRAJECTORY_COLUMNS
from mission.sim import kinematics
from mission.sim.faults import DVL_LOST_DRIFT_M_S, ActiveFaults, EmitFn, degraded, restamp
from mission.sim.kinematics import TrueState
from mission.vehicle import (
    HOVER_GAIN,
    STATION_KEEPING_SPEED_M_S,
    Command,
    NavState,
    Observation,
    ScanFrame,
    SonarPing,
)
from mission.world.scene import Scene

HEADING_SIGMA_DEG = 0.3
DEPTH_SIGMA_M = 0.02
ALTITUDE_SIGMA_M = 0.05
USBL_OUTLIER_RATE = 0.02  # multipath: this share of fixes is off by several sigma



@dataclass
class UsblFix:
    time: float
    north: float
    east: float
    used: bool
    accepted: bool


@dataclass
class SimLog:
    rows: list[tuple[object, ...]] = field(default_factory=list)
    fixes: list[UsblFix] = field(default_factory=list)
    seabed_contacts: int = 0
    pings: int = 0
    frames: list[tuple[float, Any]] = field(default_factory=list)  # (time, true T_world_left) of each pair
    scans: list[tuple[float, Any, Any]] = field(default_factory=list)  # (time, true origin, true object hits)


NEXT_SAMPLE = {"mbes": "next_ping", "stereo": "next_frame", "scanner": "next_scan"}  # sensor → its next due time


class SimulatedVehicle:
    """A kinematic AUV in a scene. `element` is set by the runner so that log rows say what was running."""

    def __init__(self, mission: Mission, scene: Scene, seed: int, dt: float = 0.2):
        self.mission = mission
        self.scene = scene
        self.control_period = dt
        self.rng = random.Random(seed)
        home = mission.home
        self.truth = TrueState(0.0, home.north, home.east, home.depth, home.heading % 360.0, 0.0)
        dvl = mission.sensors.dvl
        usbl = mission.sensors.usbl
        # DVL/INS error as a fixed scale factor and misalignment whose combined size is the configured drift.
        f = dvl.drift_percent / 100.0
        theta = self.rng.uniform(0.0, 2.0 * math.pi)
        self.dvl_scale, self.dvl_misalign = f * math.cos(theta), f * math.sin(theta)
        self.dvl_sigma = dvl.velocity_sigma
        self.dvl_max_altitude = dvl.max_altitude
        self.usbl_sigma = usbl.sigma if usbl else 0.0
        self.usbl_period = 1.0 / usbl.rate_hz if usbl else math.inf
        self.next_fix = self.usbl_period
        self.aiding = usbl is not None
        self.filter = NavigationFilter(home.north, home.east, max(self.usbl_sigma, 1.0), f, self.dvl_sigma)
        self.command = Command(self.truth.heading, 0.0, home.depth)
        self.energy_used_wh = 0.0
        self.distance_m = 0.0
        self.element = ""
        self.payload: frozenset[str] = frozenset()
        self.mbes: Any = None
        self.next_ping = 0.0
        self.pending_pings: list[SonarPing] = []
        self.camera: Any = None
        self.next_frame = 0.0
        self.pending_frames: list[StereoImages] = []
        self.scanner: Any = None
        self.next_scan = 0.0
        self.pending_scans: list[ScanFrame] = []
        self.frame_rate_hz = mission.sensors.stereo.rate_hz if mission.sensors.stereo is not None else 1.0
        self.frame_sink: Any = None  # called as sink(images, true T_world_left) with each pair (stereo recording)
        self.log = SimLog()
        self.faults = ActiveFaults(mission.faults, mission.vehicle.energy_wh)
        self.on_event: EmitFn | None = None  # the runner's event log: fault_started / fault_ended
        self.row_sink: Callable[[tuple[object, ...]], None] | None = None  # each log row as it is made (streaming)
        self._last_output: dict[str, Any] = {}  # each payload sensor's last output (what a frozen one repeats)
        self._floor = functools.lru_cache(maxsize=1)(scene.surface.depth_at)  # asked thrice a step at one place
        self._measure()

    # -- sensors ---------------------------------------------------------------------------------------------
    def true_altitude(self) -> float:
        t = self.truth
        return self._floor(t.north, t.east) - t.depth  # `Scene.altitude`, with the floor looked up once a step

    def _measure(self) -> None:
        t = self.truth
        self.heading_meas = (t.heading + self.rng.gauss(0.0, HEADING_SIGMA_DEG)) % 360.0
        self.depth_meas = max(t.depth + self.rng.gauss(0.0, DEPTH_SIGMA_M), 0.0)
        alt = self.true_altitude()
        self.altitude_meas = alt + self.rng.gauss(0.0, ALTITUDE_SIGMA_M) \
            if 0.0 < alt <= self.dvl_max_altitude and not self.faults.dvl_out else None

    def _dvl_velocity_world(self) -> tuple[float, float]:
        """Velocity over ground as the DVL measures it (body frame, biased), rotated by the measured heading."""
        t = self.truth
        h = math.radians(t.heading)
        c, s = math.cos(h), math.sin(h)
        forward = c * t.v_north + s * t.v_east
        starboard = -s * t.v_north + c * t.v_east
        k = 1.0 + self.dvl_scale
        ca, sa = math.cos(self.dvl_misalign), math.sin(self.dvl_misalign)
        fwd_m = k * (ca * forward - sa * starboard) + self.rng.gauss(0.0, self.dvl_sigma)
        stb_m = k * (sa * forward + ca * starboard) + self.rng.gauss(0.0, self.dvl_sigma)
        hm = math.radians(self.heading_meas)
        cm, sm = math.cos(hm), math.sin(hm)
        return cm * fwd_m - sm * stb_m, sm * fwd_m + cm * stb_m

    def _usbl(self) -> None:
        t = self.truth
        sigma = self.usbl_sigma
        if self.rng.random() < USBL_OUTLIER_RATE:
            sigma *= 8.0
        fix = UsblFix(t.time, t.north + self.rng.gauss(0.0, sigma), t.east + self.rng.gauss(0.0, sigma),
                      used=self.aiding, accepted=False)
        if self.aiding:
            fix.accepted = self.filter.update(fix.north, fix.east, self.usbl_sigma).accepted
        self.log.fixes.append(fix)

    # -- the Vehicle interface -----------------------------------------------------------------------------
    def _ping(self) -> None:
        """Multibeam pings due by now: cast from the true pose, tagged with the estimated pose."""
        period = 1.0 / self.mbes.effective_rate_hz
        t, f = self.truth, self.filter
        while self.next_ping <= t.time + 1e-9:
            ping = self.mbes.ping(t.north, t.east, t.depth, t.heading)
            ranges = np.where(ping.hit, ping.ranges, self.mbes.max_range)  # no return: free out to max range
            self.pending_pings.append(SonarPing(
                time=t.time, ranges=ranges, angles_deg=ping.angles_deg, hit=ping.hit, north=f.north,
                east=f.east, depth=self.depth_meas, heading=self.heading_meas, position_sigma=f.sigma))
            self.log.pings += 1
            self.next_ping += period

    def _scan(self) -> None:
        """Scanner frames due by now: cast from the true pose, tagged with the estimated pose; the true surface
        points the rays hit on objects go to the log (for metrics), not to the agent."""
        t, f = self.truth, self.filter
        while self.next_scan <= t.time + 1e-9:
            frame = self.scanner.scan(t.north, t.east, t.depth, t.heading)
            ranges = np.where(frame.hit, frame.ranges, self.scanner.max_range)
            self.pending_scans.append(ScanFrame(
                time=t.time, ranges=ranges, directions_body=frame.directions_body, hit=frame.hit,
                max_range=self.scanner.max_range, north=f.north, east=f.east, depth=self.depth_meas,
                heading=self.heading_meas, position_sigma=f.sigma))
            on_object = frame.object_ids != ""
            self.log.scans.append((t.time, frame.origin_ned, frame.true_points_ned[on_object].astype(np.float32)))
            self.next_scan += self.scanner.period_s

    def _capture(self) -> None:
        """A stereo pair rendered from the true pose; the truth of its pose goes to the log, not the agent."""
        t = self.truth
        if t.time + 1e-9 < self.next_frame:
            return
        frame = self.camera.render(t.north, t.east, t.depth, t.heading)
        self.pending_frames.append(StereoImages(t.time, frame.left, frame.right, frame.K, frame.baseline))
        self.log.frames.append((t.time, frame.T_world_left))
        if self.frame_sink is not None:
            self.frame_sink(self.pending_frames[-1], frame.T_world_left)
        self.next_frame = t.time + 1.0 / self.frame_rate_hz

    def observe(self) -> Observation:
        f = self.filter
        pings, self.pending_pings = tuple(self.pending_pings), []
        frames, self.pending_frames = tuple(self.pending_frames), []
        scans, self.pending_scans = tuple(self.pending_scans), []
        return Observation(NavState(
            time=self.truth.time, north=f.north, east=f.east, depth=self.depth_meas, heading=self.heading_meas,
            speed=self.truth.speed, altitude=self.altitude_meas, position_sigma=f.sigma,
            energy_wh=self.mission.vehicle.energy_wh - self.energy_used_wh), sonar=pings, stereo=frames,
            scans=scans)

    def apply(self, command: Command) -> None:
        self.command = command

    def set_aiding(self, usbl: bool) -> None:
        self.aiding = usbl and self.usbl_sigma > 0.0

    def set_payload(self, sensors: frozenset[str]) -> None:
        for name in (sensors - self.payload) & NEXT_SAMPLE.keys():  # switched on: no burst of the missed samples
            setattr(self, NEXT_SAMPLE[name], max(getattr(self, NEXT_SAMPLE[name]), self.truth.time))
        self.payload = sensors
        if "mbes" in sensors and self.mbes is None and self.mission.sensors.mbes is not None:
            from mission.sim.mbes import Multibeam
            from mission.sim.mjworld import mjworld_for

            world = mjworld_for(self.scene)
            self.mbes = Multibeam.from_settings(world, self.mission.sensors.mbes, seed=self.rng.randrange(2**31))
            self.next_ping = self.truth.time
        if "stereo" in sensors and self.camera is None and self.mission.sensors.stereo is not None:
            from mission.sim.camera import StereoCamera
            from mission.sim.mjworld import mjworld_for

            self.camera = StereoCamera(mjworld_for(self.scene), self.mission.sensors.stereo,
                                       texture=self.scene.texture, depth=False)  # no one reads it here
        if "stereo" in sensors:
            self.next_frame = max(self.next_frame, self.truth.time)
        if "scanner" in sensors and self.scanner is None and self.mission.sensors.scanner is not None:
            from mission.sim.scanner import Scanner3D

            self.scanner = Scanner3D.from_settings(self.scene, self.mission.sensors.scanner,
                                                   seed=self.rng.randrange(2**31))
        if "scanner" in sensors:
            self.next_scan = max(self.next_scan, self.truth.time)

    def set_frame_rate(self, rate_hz: float | None) -> None:
        own = self.mission.sensors.stereo.rate_hz if self.mission.sensors.stereo is not None else 1.0
        self.frame_rate_hz = own if rate_hz is None else min(max(rate_hz, 1e-3), own)

    def _sense_payload(self) -> None:
        """The payload sensors due now: each measures, or, lost or frozen, delivers nothing or its last output."""
        f = self.filter
        for key, device, pending, sense, due in (
                ("mbes", self.mbes, self.pending_pings, self._ping, "next_ping"),
                ("stereo", self.camera, self.pending_frames, self._capture, "next_frame"),
                ("scanner", self.scanner, self.pending_scans, self._scan, "next_scan")):
            if device is None or key not in self.payload:
                continue
            if key not in self.faults.lost | self.faults.frozen:
                sense()
                self._last_output.update({key: pending[-1]} if pending else {})
            elif self.truth.time + 1e-9 >= getattr(self, due):
                last = self._last_output.get(key)
                if key in self.faults.frozen and last is not None:  # re-stamped, sonar and scans re-tagged
                    tags = {} if key == "stereo" else {"north": f.north, "east": f.east, "depth": self.depth_meas,
                                                       "heading": self.heading_meas, "position_sigma": f.sigma}
                    pending.append(restamp(last, self.truth.time, **tags))
                period = 1.0 / (self.mbes.effective_rate_hz if key == "mbes" else self.frame_rate_hz) \
                    if key != "scanner" else self.scanner.period_s
                setattr(self, due, self.truth.time + period)

    def _dead_reckon(self, dt: float) -> None:
        """The navigation's prediction: on the DVL, or without it on the propeller's speed through the water."""
        if not self.faults.dvl_out:
            self.filter.predict(*self._dvl_velocity_world(), dt)
            return
        h = math.radians(self.heading_meas)
        self.filter.predict(self.truth.speed * math.cos(h), self.truth.speed * math.sin(h), dt)
        grown = self.filter.sigma + DVL_LOST_DRIFT_M_S * dt
        self.filter.var = grown * grown

    def advance(self) -> None:
        dt = self.control_period
        self.energy_used_wh += self.faults.update(self.truth.time + dt, self.on_event)  # acting over this step
        fraction = self.faults.thrust_fraction
        cmd, t, v = self.command, self.truth, degraded(self.mission.vehicle, fraction)
        if cmd.altitude is not None and self.altitude_meas is not None:
            depth_cmd = self.depth_meas + (self.altitude_meas - cmd.altitude)
        else:
            depth_cmd = cmd.depth if cmd.depth is not None else self.depth_meas
        n0, e0, d0 = t.north, t.east, t.depth
        hover = None
        if cmd.station is not None:  # station keeping on the estimate
            en, ee = cmd.station[0] - self.filter.north, cmd.station[1] - self.filter.east
            gain = min(HOVER_GAIN, STATION_KEEPING_SPEED_M_S / max(math.hypot(en, ee), 1e-9)) * fraction
            hover = (gain * en, gain * ee)
        kinematics.step(t, cmd.heading, cmd.speed, depth_cmd, self.heading_meas, self.depth_meas, v,
                        self.scene.current, dt, hover)
        floor = self._floor(t.north, t.east)
        if t.depth > floor:  # the kinematic model cannot pass through the seabed; count the contact
            t.depth = floor
            self.log.seabed_contacts += 1
        self.distance_m += math.sqrt((t.north - n0) ** 2 + (t.east - e0) ** 2 + (t.depth - d0) ** 2)
        ratio = t.speed / self.mission.vehicle.cruise_speed
        self.energy_used_wh += (v.hotel_power_w + v.propulsion_power_w * ratio * ratio * ratio) * dt / 3600.0
        self._measure()
        self._dead_reckon(dt)
        if t.time >= self.next_fix - 1e-9:
            self.next_fix += self.usbl_period
            if not self.faults.usbl_out:
                self._usbl()
        self._sense_payload()
        self.record()

    def record(self) -> None:
        t, f = self.truth, self.filter
        row = (t.time, t.north, t.east, t.depth, t.heading, self.true_altitude(),
               f.north, f.east, self.depth_meas, self.heading_meas,
               self.altitude_meas if self.altitude_meas is not None else math.nan,
               f.sigma, t.speed, self.energy_used_wh, self.element)
        self.log.rows.append(row)
        if self.row_sink is not None:
            self.row_sink(row)
