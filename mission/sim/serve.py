"""`auv sim serve`: the simulated vehicle behind MAVLink, as ArduPilot's SITL serves a simulated autopilot.

`serve` runs `SimulatedVehicle` (its navigation errors included) in wall-clock time × `speedup`, and speaks
ArduSub's side of MAVLink through `mission.sim.autopilot.SimAutopilot` on one or more pymavlink links
(`udpout:127.0.0.1:14550`, `udpin:…`, `tcp:…`): telemetry goes to every link, answers to the link asked.
The vehicle's clock (`time_boot_ms`) is the simulated clock. With `out`, the truth is written as it goes
(`mission.runfolder.prepare_run_folder`, then `mission.sim.truth_log`) and what the autopilot did goes to
`autopilot.jsonl`. The truth never crosses the link. With `zenoh` (endpoints to listen on), the payload streams
(multibeam, scanner, stereo) go out on Zenoh too (`mission.sim.publish`), stamped with the vehicle's clock.
"""

from __future__ import annotations

import select
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mission.errors import AuvError, VehicleError
from mission.events import EventLog
from mission.language.loader import load_world
from mission.language.models import Mission
from mission.sim.autopilot import FS_GCS_TIMEOUT, SimAutopilot
from mission.sim.vehicle import SimulatedVehicle
from mission.vehicles.mavlink_link import connect
from mission.world.scene import build_scene

SYSTEM_ID = 1
COMPONENT_AUTOPILOT = 1
MAX_LAG = 1.0  # s of wall time: further behind than this, the pacing restarts rather than racing to catch up


@dataclass
class ServeSummary:
    """What a serve did: simulated and wall time, steps, and the autopilot's log (mode changes, failsafes)."""

    sim_time: float = 0.0
    wall_time: float = 0.0
    steps: int = 0
    events: list[dict[str, Any]] = field(default_factory=list)
    published: dict[str, int] = field(default_factory=dict)  # payload frames published per sensor (Zenoh)


class _Links:
    """The pymavlink connections of one served vehicle."""

    def __init__(self, addresses: Sequence[str]):
        self.conns: list[Any] = []
        try:
            for a in addresses:
                self.conns.append(connect(a, SYSTEM_ID, COMPONENT_AUTOPILOT))
        except VehicleError:
            self.close()
            raise

    def send_all(self, name: str, *args: Any) -> None:
        for c in self.conns:
            _send(c, name, *args)

    def poll(self, timeout: float) -> list[tuple[Any, Any]]:
        """Messages that arrive within `timeout` (s), with the connection each came on."""
        fds = [c.fd for c in self.conns if getattr(c, "fd", None) is not None]
        if timeout > 0:
            if len(fds) == len(self.conns):
                select.select(fds, [], [], timeout)
            else:  # serial links without a selectable descriptor: poll
                time.sleep(min(timeout, 0.005))
        out = []
        for c in self.conns:
            while True:
                try:
                    msg = c.recv_msg()
                except (OSError, ValueError):
                    break  # e.g. ICMP port unreachable while nobody listens on a udpout port yet
                if msg is None:
                    break
                if msg.get_type() != "BAD_DATA":
                    out.append((c, msg))
        return out

    def close(self) -> None:
        for c in self.conns:
            try:
                c.close()
            except OSError:
                pass


def _send(conn: Any, name: str, *args: Any) -> None:
    try:
        getattr(conn.mav, f"{name}_send")(*args)
    except OSError:
        pass  # nobody listening (yet): UDP telemetry is fire and forget, as on a real vehicle


def serve(mission: Mission, address: str | Sequence[str], seed: int | None = None, speedup: float = 1.0,
          out: str | Path | None = None, stop_event: threading.Event | None = None,
          gcs_timeout: float = FS_GCS_TIMEOUT, dt: float = 0.2,
          on_event: Callable[[dict[str, Any]], None] | None = None, zenoh: Sequence[str] = (),
          zenoh_prefix: str = "auv/sim", streams_stop: threading.Event | None = None,
          force: bool = False) -> ServeSummary:
    """Serve `mission`'s simulated vehicle on `address` (one pymavlink connection string or several) until
    `stop_event` is set; returns what happened. `on_event` sees each autopilot event as it happens. With `zenoh`
    endpoints (`tcp/127.0.0.1:7447`), the payload streams are published under `zenoh_prefix`; setting
    `streams_stop` ends them (the Zenoh session closes, as if the payload computer died) while the vehicle goes on."""
    if mission.world is None:
        raise AuvError(f"mission '{mission.name}' names no world; serving it needs `world:`")
    if speedup <= 0:
        raise AuvError(f"--speedup must be positive (got {speedup:g})")
    seed = mission.seed if seed is None else seed
    stop = stop_event or threading.Event()
    vehicle = SimulatedVehicle(mission, build_scene(load_world(mission.world)), seed, dt)
    out_dir = Path(out) if out is not None else None
    truth = events = lock = None
    if out_dir is not None:
        from mission.runfolder import prepare_run_folder
        from mission.sim.truth_log import TruthLog

        lock = prepare_run_folder(out_dir, mission, seed, force=force, kind="auv sim serve")  # held while serving
        truth = TruthLog(out_dir)
        events = EventLog(out_dir / "autopilot.jsonl")
    vehicle.log.rows.clear()
    summary = ServeSummary()
    links = _Links([address] if isinstance(address, str) else list(address))

    def log(event: str, **fields: Any) -> None:
        record = {"time": round(vehicle.truth.time, 3), "event": event, **fields}
        summary.events.append(record)
        if events is not None:
            events.emit(event, vehicle.truth.time, **fields)
        if on_event is not None:
            on_event(record)

    # the simulated GPS needs a place on the globe, as SITL's default home: (0, 0) for a mission without `origin`
    where = (mission.origin.lat, mission.origin.lon) if mission.origin is not None else (0.0, 0.0)
    autopilot = SimAutopilot(vehicle, where, links.send_all, log,
                             gcs_timeout=gcs_timeout)
    streams = None
    if zenoh:
        from mission.sim.publish import StreamPublisher

        try:
            streams = StreamPublisher(vehicle, list(zenoh), zenoh_prefix, log)
        except BaseException:
            links.close()
            raise
    wall0 = base = time.monotonic()
    base_steps = 0
    next_beat = wall0
    try:
        while not stop.is_set():
            due = base + (summary.steps - base_steps) * dt / speedup
            while True:  # answer the links until the next step is due (at once, not at the next step)
                now = time.monotonic()
                for conn, msg in links.poll(max(due - now, 0.0)):
                    autopilot.handle(msg, lambda name, *args, c=conn: _send(c, name, *args))
                if time.monotonic() >= due or stop.is_set():
                    break
            now = time.monotonic()
            if now - due > MAX_LAG:
                base, base_steps = now, summary.steps
            vehicle.advance()
            summary.steps += 1
            autopilot.check()
            autopilot.telemetry(dt)
            if streams is not None and streams_stop is not None and streams_stop.is_set():
                summary.published = dict(streams.published)
                streams.close()
                streams = None
                log("streams_stopped")
            if streams is not None:
                streams.publish()
            if now >= next_beat:
                autopilot.heartbeat()
                next_beat = now + 1.0
            if truth is not None:
                truth.take(vehicle.log)
            else:
                vehicle.log.rows.clear()
                vehicle.log.fixes.clear()
    finally:
        links.close()
        if streams is not None:
            streams.close()
            summary.published = dict(streams.published)
        if truth is not None:
            truth.close()
        if events is not None:
            events.close()
        if lock is not None:
            lock.release()
    summary.sim_time = vehicle.truth.time
    summary.wall_time = time.monotonic() - wall0
    return summary


class ServedVehicle:
    """`serve` in a background thread, for tests and notebooks: `with ServedVehicle(mission, address, speedup=20)
    as served: …` starts it, leaving the block stops it (and re-raises what the server raised). `events` grows as
    the autopilot logs (mode changes, arming, EKF source sets, GCS failsafe)."""

    def __init__(self, mission: Mission, address: str | Sequence[str], **kwargs: Any):
        self.stop_event = threading.Event()
        self.events: list[dict[str, Any]] = []
        self.summary: ServeSummary | None = None
        self.error: BaseException | None = None
        self._args = (mission, address)
        self._kwargs = kwargs
        self._thread = threading.Thread(target=self._run, name="auv-sim-serve", daemon=True)

    def _run(self) -> None:
        try:
            self.summary = serve(*self._args, stop_event=self.stop_event, on_event=self.events.append,
                                 **self._kwargs)
        except BaseException as exc:  # handed to the thread that stops the server
            self.error = exc

    def start(self) -> ServedVehicle:
        self._thread.start()
        return self

    def stop(self, timeout: float = 5.0) -> ServeSummary | None:
        self.stop_event.set()
        self._thread.join(timeout)
        if self.error is not None:
            raise self.error
        return self.summary

    def __enter__(self) -> ServedVehicle:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()
