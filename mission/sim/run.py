"""Simulate a mission end to end and write its run folder (the output contract of `auv simulate`)."""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mission.action_results import add_action_results, mapped_elements
from mission.agents import REGISTRY
from mission.errors import AuvError, RunFolderError, UnsupportedMissionError
from mission.events import EventLog
from mission.executive import ExecutionReport, Executive
from mission.interrupt import Interrupted, SignalStop, signal_name, stop_on_signals
from mission.language.loader import load_world
from mission.language.models import Mission
from mission.plugin_calls import SIMULATED_LATENCY_S
from mission.plugin_host import PluginHost
from mission.plugin_settings import plugin_settings
from mission.runfolder import TrajectoryWriter, prepare_run_folder
from mission.sim.metrics import run_metrics
from mission.sim.vehicle import SimulatedVehicle
from mission.vehicle import NavState
from mission.world.scene import Scene, build_scene


@dataclass
class RunResult:
    metrics: dict[str, Any]
    report: ExecutionReport
    vehicle: SimulatedVehicle
    scene: Scene
    out: Path | None
    signal: int | None = None  # the signal that stopped the run, if one did (`metrics["interrupted"]`)


def check_supported(mission: Mission) -> None:
    """Refuse, before anything starts, a mission whose route uses kinds with no agent yet."""
    missing = [e for e in mission.route if e.kind not in REGISTRY]
    if missing:
        kinds = sorted({e.kind for e in missing})
        where = ", ".join(f"{e.id} ({e.kind})" for e in missing)
        raise UnsupportedMissionError(
            f"cannot simulate '{mission.name}': route element kind(s) {', '.join(kinds)} not supported yet "
            f"(used by {where}); supported: {', '.join(sorted(REGISTRY))}")


DEFAULT_PLUGIN_LATENCY_S = SIMULATED_LATENCY_S


def simulate(mission: Mission, seed: int | None = None, out: str | Path | None = None, plots: bool = True,
             progress: bool = False, dt: float = 0.2, record_stereo: bool = False,
             plugin_latency_s: float | None = DEFAULT_PLUGIN_LATENCY_S, force: bool = False,
             signals: bool = False) -> RunResult:
    """Run `mission` in its world with a simulated vehicle; with `out`, write the run folder there (claimed and
    locked for the run: `mission.runlock`; `force` replaces an earlier run's folder), and with `record_stereo`, the
    stereo stream in `out/stereo/` (KITTI layout: `mission.sim.stereo_record`).

    The trajectory and the events are written as the run goes; `metrics.json`, then the `mission_finished` event,
    end the folder. With `signals`, SIGINT/SIGTERM stop the run cleanly (`mission.interrupt`): the folder gets an
    `interrupted` event and `metrics.json` with `"interrupted": true`, and `RunResult.signal` says which signal; a
    second signal raises `Interrupted` after writing the same.

    Perception plug-ins run in worker processes and each call's latency is charged to the simulated clock:
    `plugin_latency_s` per call (a run then repeats exactly for its seed), or with None the call's measured CPU
    time (closer to this plug-in's cost, but the run depends on the machine and its load)."""
    check_supported(mission)
    if mission.world is None:
        raise AuvError(f"mission '{mission.name}' names no world; simulation needs `world:`")
    if record_stereo and out is None:
        raise AuvError("recording the stereo stream needs a run folder (`out`)")
    seed = mission.seed if seed is None else seed
    with stop_on_signals(None, install=signals) as stop:
        scene = build_scene(load_world(mission.world))
        vehicle = SimulatedVehicle(mission, scene, seed, dt)
        out_dir = Path(out) if out is not None else None
        lock = prepare_run_folder(out_dir, mission, seed, force=force) if out_dir is not None else None
        try:
            return _run(mission, seed, vehicle, scene, out_dir, stop, plots, progress, record_stereo,
                        plugin_latency_s)
        except OSError as exc:  # a file of the run folder could not be written (disk full, removed under us)
            where = Path(str(exc.filename)).resolve() if exc.filename is not None else None
            if out_dir is None or where is None or out_dir.resolve() not in where.parents:
                raise
            raise RunFolderError(f"{exc.filename}: cannot write ({exc.strerror or exc})") from exc
        finally:
            if lock is not None:
                lock.release()


def _run(mission: Mission, seed: int, vehicle: SimulatedVehicle, scene: Scene, out_dir: Path | None,
         stop: SignalStop, plots: bool, progress: bool, record_stereo: bool,
         plugin_latency_s: float | None) -> RunResult:
    writer = TrajectoryWriter(out_dir / "trajectory.csv") if out_dir is not None else None
    vehicle.row_sink = writer.write if writer is not None else None
    recorder = None
    if record_stereo and out_dir is not None:
        from mission.sim.stereo_record import record_vehicle_stereo

        recorder = record_vehicle_stereo(vehicle, out_dir / "stereo")
    log = EventLog(out_dir / "events.jsonl" if out_dir else None)
    bar = _progress_bar(mission) if progress else None
    finished: dict[str, Any] = {}  # the executive's mission_finished: logged once the results are written

    def emit(event: str, t: float, **fields: Any) -> None:
        if event == "mission_finished":
            finished.update(time=t, **fields)
            return
        if event == "element_started":
            vehicle.element = str(fields.get("element", ""))
        log.emit(event, t, **fields)
        if bar is not None and event.startswith("element"):
            bar.set_postfix_str(f"{fields.get('element', '')}: {event.split('_')[1]}")

    def tick(nav: NavState) -> None:
        if bar is not None and int(nav.time) > bar.n:
            bar.update(int(nav.time) - bar.n)

    vehicle.on_event = emit
    wall0 = time.perf_counter()
    host: PluginHost | None = None
    executive: Executive | None = None
    try:
        try:
            host = PluginHost(mission.plugins.model_dump(), plugin_settings(mission), emit, simulated_clock=True,
                              latency_s=plugin_latency_s) if any(mission.plugins.model_dump().values()) else None
            from mission.artifacts import Artifacts

            executive = Executive(mission, vehicle, emit, on_tick=tick, plugins=host, artifacts=Artifacts(out_dir))
            stop.target = executive.request_stop
            report = executive.run()
            stop.target = None
        finally:
            stop.closing = True  # what follows writes the folder's end: later signals wait for it
            if host is not None:
                host.close()  # the workers go, whatever ended the run
            if recorder is not None:
                recorder.close()
            if bar is not None:
                bar.close()
        metrics = run_metrics(mission.name, seed, report, vehicle, scene, time.perf_counter() - wall0)
        if host is not None:
            metrics["plugins"] = host.stats()
        if stop.signum is not None:
            metrics.update(interrupted=True, signal=signal_name(stop.signum))
        mapped = mapped_elements(mission) & set(report.knowledge.maps) if out_dir is not None else set()
        add_action_results(metrics, mission, report, mapped)
        if out_dir is not None and writer is not None:
            from mission.runfolder import write_run_results
            from mission.sim.photos import write_photos

            writer.close()
            write_photos(out_dir, report.knowledge, vehicle)  # photo surveys' pairs: photos/, out of the maps
            if stop.signum is not None:
                log.emit("interrupted", vehicle.truth.time, signal=signal_name(stop.signum))
            write_run_results(out_dir, metrics, None, vehicle.log.fixes, report.knowledge, mapped)
        log.emit("mission_finished", finished.pop("time", vehicle.truth.time), **finished)
    except Interrupted as exc:
        stop.closing = True
        _write_interrupted(mission, seed, executive, vehicle, scene, out_dir, writer, log, exc.signum, wall0)
        log.close()
        raise
    finally:
        if writer is not None:
            writer.close()
        log.close()
    stop.closing = False
    if out_dir is not None and plots:
        from mission.plots import plot_run

        plot_run(out_dir)
    return RunResult(metrics, report, vehicle, scene, out_dir, stop.signum)


def _write_interrupted(mission: Mission, seed: int, executive: Executive | None, vehicle: SimulatedVehicle,
                       scene: Scene, out_dir: Path | None, writer: TrajectoryWriter | None, log: EventLog,
                       signum: int, wall0: float) -> None:
    """A run cut short at once: what is known so far, marked interrupted, and the end of the event log."""
    report = executive.report if executive is not None else ExecutionReport()
    report.end_time = vehicle.truth.time
    try:
        metrics = run_metrics(mission.name, seed, report, vehicle, scene, time.perf_counter() - wall0)
    except Exception as exc:  # noqa: BLE001 - a report cut mid-element may lack figures; the head still matters
        metrics = {"mission": mission.name, "seed": seed, "metrics_error": f"{type(exc).__name__}: {exc}",
                   "mission_time_s": round(vehicle.truth.time, 2), "distance_m": round(vehicle.distance_m, 2),
                   "energy_wh": round(vehicle.energy_used_wh, 2)}
    metrics.update(completed=False, aborted=True, interrupted=True, signal=signal_name(signum))
    log.emit("interrupted", vehicle.truth.time, signal=signal_name(signum))
    if out_dir is not None and writer is not None:
        from mission.runfolder import write_run_results

        writer.close()
        write_run_results(out_dir, metrics, None, vehicle.log.fixes, report.knowledge, mapped_elements(mission))
    log.emit("mission_finished", vehicle.truth.time, completed=False, aborted=True, interrupted=True,
             reason=f"interrupted by {signal_name(signum)}")


def _progress_bar(mission: Mission) -> Any:
    from tqdm import tqdm

    return tqdm(total=int(mission.safety.max_duration), unit="sim s", desc=mission.name, leave=False,
                mininterval=0.5, bar_format="{desc}: {n_fmt} sim s [{elapsed}, {rate_fmt}] {postfix}")
