"""Simulate a mission end to end and write its run folder (the output contract of `auv simulate`)."""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mission.agents import REGISTRY
from mission.errors import AuvError, UnsupportedMissionError
from mission.events import EventLog
from mission.executive import ExecutionReport, Executive
from mission.language.loader import load_world
from mission.language.models import Mission
from mission.plugin_calls import SIMULATED_LATENCY_S
from mission.plugin_host import PluginHost
from mission.plugin_settings import plugin_settings
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
             plugin_latency_s: float | None = DEFAULT_PLUGIN_LATENCY_S) -> RunResult:
    """Run `mission` in its world with a simulated vehicle; with `out`, write the run folder there (and with
    `record_stereo`, the stereo stream in `out/stereo/`, KITTI layout: `mission.sim.stereo_record`).

    Perception plug-ins run in worker processes and each call's latency is charged to the simulated clock:
    `plugin_latency_s` per call (a run then repeats exactly for its seed), or with None the call's measured CPU
    time (closer to this plug-in's cost, but the run depends on the machine and its load)."""
    check_supported(mission)
    if mission.world is None:
        raise AuvError(f"mission '{mission.name}' names no world; simulation needs `world:`")
    if record_stereo and out is None:
        raise AuvError("recording the stereo stream needs a run folder (`out`)")
    seed = mission.seed if seed is None else seed
    scene = build_scene(load_world(mission.world))
    vehicle = SimulatedVehicle(mission, scene, seed, dt)
    out_dir = Path(out) if out is not None else None
    if out_dir is not None:
        from mission.runfolder import prepare_run_folder

        prepare_run_folder(out_dir, mission, seed)
    recorder = None
    if record_stereo and out_dir is not None:
        from mission.sim.stereo_record import record_vehicle_stereo

        recorder = record_vehicle_stereo(vehicle, out_dir / "stereo")
    log = EventLog(out_dir / "events.jsonl" if out_dir else None)
    bar = _progress_bar(mission) if progress else None

    def emit(event: str, t: float, **fields: Any) -> None:
        if event == "element_started":
            vehicle.element = str(fields.get("element", ""))
        log.emit(event, t, **fields)
        if bar is not None and event.startswith("element"):
            bar.set_postfix_str(f"{fields.get('element', '')}: {event.split('_')[1]}")

    def tick(nav: NavState) -> None:
        if bar is not None and int(nav.time) > bar.n:
            bar.update(int(nav.time) - bar.n)

    wall0 = time.perf_counter()
    host: PluginHost | None = None
    try:
        host = PluginHost(mission.plugins.model_dump(), plugin_settings(mission), emit, simulated_clock=True,
                          latency_s=plugin_latency_s) \
            if any(mission.plugins.model_dump().values()) else None
        from mission.artifacts import Artifacts

        report = Executive(mission, vehicle, emit, on_tick=tick, plugins=host, artifacts=Artifacts(out_dir)).run()
    finally:
        if host is not None:
            host.close()  # the workers go, whatever ended the run
        log.close()
        if recorder is not None:
            recorder.close()
        if bar is not None:
            bar.close()
    wall = time.perf_counter() - wall0
    metrics = run_metrics(mission.name, seed, report, vehicle, scene, wall)
    if host is not None:
        metrics["plugins"] = host.stats()
    if out_dir is not None:
        from mission.runfolder import write_run_results
        from mission.sim.photos import write_photos

        write_photos(out_dir, report.knowledge, vehicle)  # photo surveys' pairs: photos/, out of the maps
        write_run_results(out_dir, metrics, vehicle.log.rows, vehicle.log.fixes, report.knowledge)
        if plots:
            from mission.plots import plot_run

            plot_run(out_dir)
    return RunResult(metrics, report, vehicle, scene, out_dir)


def _progress_bar(mission: Mission) -> Any:
    from tqdm import tqdm

    return tqdm(total=int(mission.safety.max_duration), unit="sim s", desc=mission.name, leave=False,
                mininterval=0.5, bar_format="{desc}: {n_fmt} sim s [{elapsed}, {rate_fmt}] {postfix}")
