"""`auv run MISSION --vehicle URI`: the executive flies a mission on a vehicle, paced by the vehicle's clock.

The run folder is written as the run goes: `events.jsonl` flushed per event, `trajectory.csv` (the estimate; the
true columns stay empty) flushed at least every second, `metrics.json` at the end (`mission.onboard.report`).
A `kill -9` therefore loses at most the last second of the trajectory. SIGINT and SIGTERM ask the executive to
stop: the vehicle is told to hold, then to surface if the mission's `on_violation` says so; a second SIGINT
interrupts at once.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mission.action_results import add_action_results
from mission.agents import REGISTRY
from mission.artifacts import Artifacts
from mission.errors import MissionError, UnsupportedMissionError
from mission.events import EventLog
from mission.executive import ExecutionReport, Executive, unsupported_elements
from mission.faults import faults_diagnostic
from mission.interrupt import signal_name, stop_on_signals
from mission.language.models import Mission
from mission.onboard.report import onboard_metrics
from mission.onboard.streamed import StreamedVehicle, guarded_agents
from mission.plugin_host import PluginHost
from mission.plugin_settings import plugin_settings
from mission.runfolder import TrajectoryWriter, prepare_run_folder, write_metrics
from mission.sensors.streams import open_streams
from mission.vehicle import Command, Observation
from mission.vehicles import OnboardVehicle, VehicleOptions, open_vehicle


@dataclass
class OnboardResult:
    metrics: dict[str, Any]
    report: ExecutionReport
    out: Path


class RecordingVehicle:
    """The adapter as the executive sees it, writing a trajectory row whenever the vehicle's clock moves on."""

    def __init__(self, vehicle: OnboardVehicle, writer: TrajectoryWriter):
        self.vehicle = vehicle
        self.writer = writer
        self.control_period = vehicle.control_period
        self.element = ""
        self.distance_m = 0.0
        self.energy_start_wh: float | None = None
        self.energy_wh = math.nan
        self._last: tuple[float, float, float, float] | None = None

    def observe(self) -> Observation:
        obs = self.vehicle.observe()
        nav = obs.nav
        if self._last is None or nav.time > self._last[0]:
            if self._last is not None:
                self.distance_m += math.dist(self._last[1:], (nav.north, nav.east, nav.depth))
            self._last = (nav.time, nav.north, nav.east, nav.depth)
            if self.energy_start_wh is None:
                self.energy_start_wh = nav.energy_wh
            self.energy_wh = nav.energy_wh
            altitude = nav.altitude if nav.altitude is not None else math.nan
            nan = math.nan
            self.writer.write((nav.time, nan, nan, nan, nan, nan, nav.north, nav.east, nav.depth, nav.heading,
                               altitude, nav.position_sigma, nav.speed, nav.energy_wh, self.element))
        return obs

    def apply(self, command: Command) -> None:
        self.vehicle.apply(command)

    def set_aiding(self, usbl: bool) -> None:
        self.vehicle.set_aiding(usbl)

    def set_payload(self, sensors: frozenset[str]) -> None:
        self.vehicle.set_payload(sensors)

    def set_frame_rate(self, rate_hz: float | None) -> None:
        self.vehicle.set_frame_rate(rate_hz)

    def advance(self) -> None:
        self.vehicle.advance()

    @property
    def energy_used_wh(self) -> float:
        if self.energy_start_wh is None or not math.isfinite(self.energy_wh):
            return 0.0
        return max(0.0, self.energy_start_wh - self.energy_wh)


def run_onboard(mission: Mission, uri: str, out: str | Path, connect_timeout: float = 10.0,
                seed: int | None = None, signals: bool = True,
                sensor_drivers: dict[str, str] | None = None, force: bool = False) -> OnboardResult:
    """Fly `mission` on the vehicle at `uri` and write the run folder `out` (see the module docstring).

    Mission sensors with a `driver:` (or an entry in `sensor_drivers`, sensor name → driver URI) get their payload
    stream (`mission.onboard.streamed`); what each stream delivered, dropped and lost goes to metrics.json under
    `sensors`.

    Raises `VehicleError` when the vehicle cannot be opened (the run folder then holds the mission and an
    event saying why), `RunFolderError` when `out` cannot be a run folder (`mission.runlock`; `force` replaces an
    earlier run's folder), and `MissionError` for a mission with `faults:` (simulation only)."""
    if mission.faults:
        raise MissionError([faults_diagnostic(mission, "`auv run` flies a real vehicle")])
    missing = unsupported_elements(mission)
    if missing:
        raise UnsupportedMissionError(
            f"cannot run '{mission.name}': no agent for {', '.join(f'{e.id} ({e.kind})' for e in missing)}")
    out = Path(out)
    seed = mission.seed if seed is None else seed
    lock = prepare_run_folder(out, mission, seed, force=force, kind="auv run")
    log = EventLog(out / "events.jsonl")
    writer = TrajectoryWriter(out / "trajectory.csv")
    recording: RecordingVehicle | None = None

    def emit(event: str, t: float, **fields: Any) -> None:
        if event == "element_started" and recording is not None:
            recording.element = str(fields.get("element", ""))
        log.emit(event, t, **fields)

    wall0 = time.perf_counter()
    host: PluginHost | None = None
    try:
        try:  # the streams first: a driver that cannot start refuses the run before the vehicle is armed
            streams = open_streams(mission, sensor_drivers)
        except Exception as exc:
            log.emit("sensor_unavailable", 0.0, reason=str(exc))
            raise
        try:
            vehicle = open_vehicle(uri, mission, VehicleOptions(connect_timeout=connect_timeout, emit=emit))
        except BaseException as exc:
            for stream in streams.values():
                stream.close()
            log.emit("vehicle_unavailable", 0.0, vehicle=uri, reason=str(exc))
            raise
        if streams:
            for name, stream in streams.items():
                emit("sensor_stream", 0.0, sensor=name, driver=stream.uri, timeout_s=stream.timeout)
            vehicle = StreamedVehicle(vehicle, streams, emit)
        recording = RecordingVehicle(vehicle, writer)
        try:
            roles = mission.plugins.model_dump()
            host = PluginHost(roles, plugin_settings(mission), emit) if any(roles.values()) else None
            agents = guarded_agents(REGISTRY, vehicle) if isinstance(vehicle, StreamedVehicle) else None
            executive = Executive(mission, recording, emit, agents=agents, plugins=host, artifacts=Artifacts(out))
            with stop_on_signals(executive.request_stop, install=signals) as stop:
                report = executive.run()
        finally:
            if host is not None:
                host.close()
            vehicle.close()
        wall = time.perf_counter() - wall0
        metrics = onboard_metrics(mission.name, seed, report, wall, recording.distance_m,
                                  recording.energy_used_wh, mission.vehicle.energy_wh)
        add_action_results(metrics, mission, report, ())  # no maps are written onboard
        if isinstance(vehicle, StreamedVehicle):
            metrics["sensors"] = vehicle.stream_metrics()
        if stop.signum is not None:
            metrics.update(interrupted=True, signal=signal_name(stop.signum))
            log.emit("interrupted", report.end_time, signal=signal_name(stop.signum))
        write_metrics(out, metrics)
    finally:
        writer.close()
        log.close()
        lock.release()
    return OnboardResult(metrics, report, out)

