"""Simulation speed, two figures (issue 24 item 3).

1. A one-hour transit-only mission (`missions/transit_hour.yaml`) with plots off must run at >= 720x real time
   (<= 5 s) in CPU time (`time.process_time`; the wall time is reported beside it, and on a machine shared with
   other jobs it can be many times the CPU time); repeated runs give the median. This is the cost of the control
   step itself.
2. The full reference mission (`missions/sps_field_inspection.yaml`: transit, multibeam survey, exploration of an
   unknown wellhead with the scanner, stereo inspection with the referencing and odometry plug-ins in worker
   processes), plots off, must run at >= 60x real time in CPU time on one core: the CPU seconds of this process
   and of the plug-in worker processes (`resource.getrusage`, SELF and CHILDREN, before and after the run), so
   that other jobs on a loaded machine do not count. `--quick` skips it (it takes about a minute of CPU).

There is no external simulator to anchor against here; the anchor is real time itself (the executive running
the same mission on a vehicle), so the ratios reported are real-time factors.
"""

from __future__ import annotations

import resource
import statistics
import time
from typing import Any

from mission.bench import REPO, check

REFERENCE = "missions/sps_field_inspection.yaml"


def _cpu_s() -> tuple[float, float]:
    """CPU seconds (user + system) of this process and of its children that have exited and been waited for."""
    own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime, children.ru_utime + children.ru_stime


def reference_mission_cpu() -> dict[str, Any]:
    """Run the reference mission once (its own seed, plots off) and measure its CPU time, simulator and plug-in
    workers apart."""
    from mission import load_mission
    from mission.sim.run import simulate

    mission = load_mission(REPO / REFERENCE)
    own0, children0 = _cpu_s()
    wall0 = time.perf_counter()
    result = simulate(mission, plots=False)  # the plug-in workers have exited (and were joined) when it returns
    wall = time.perf_counter() - wall0
    own1, children1 = _cpu_s()
    own, workers = own1 - own0, children1 - children0
    mission_time = float(result.metrics["mission_time_s"])
    return {
        "mission": REFERENCE,
        "seed": mission.seed,
        "completed": bool(result.metrics["completed"]),
        "mission_time_s": mission_time,
        "cpu_s": {"total": round(own + workers, 2), "simulator": round(own, 2), "plugin_workers": round(workers, 2)},
        "wall_time_s": round(wall, 2),
        "realtime_factor_cpu": round(mission_time / (own + workers), 1),
        "elements": {e["id"]: e["status"] for e in result.metrics["elements"]},
    }


def run(quick: bool) -> tuple[dict[str, Any], dict[str, dict[str, Any]]]:
    from mission import load_mission
    from mission.sim.run import simulate

    mission = load_mission(REPO / "missions" / "transit_hour.yaml")
    repeats = 2 if quick else 7
    walls, cpus, steps = [], [], 0
    mission_time = 0.0
    for seed in range(repeats):
        cpu0 = time.process_time()
        result = simulate(mission, seed=seed, plots=False)
        cpus.append(time.process_time() - cpu0)
        walls.append(result.metrics["wall_time_s"])
        mission_time = result.metrics["mission_time_s"]
        steps = len(result.vehicle.log.rows)
    wall, cpu = statistics.median(walls), statistics.median(cpus)
    results: dict[str, Any] = {
        "mission": "missions/transit_hour.yaml",
        "mission_time_s": mission_time,
        "control_steps": steps,
        "wall_time_s": {"median": wall, "min": min(walls), "max": max(walls), "runs": len(walls)},
        "cpu_time_s": {"median": round(cpu, 3), "min": round(min(cpus), 3), "max": round(max(cpus), 3)},
        "realtime_factor_vs_anchor": round(mission_time / wall, 1),
        "realtime_factor_cpu": round(mission_time / cpu, 1),
        "us_per_step": round(1e6 * wall / steps, 1),
        "cpu_us_per_step": round(1e6 * cpu / steps, 1),
    }
    checks = {
        "one_hour_mission_cpu_time_s": check(round(cpu, 3), "<= 5"),
        "realtime_factor": check(round(mission_time / cpu, 1), ">= 720"),
    }
    if not quick:
        reference = reference_mission_cpu()
        results["reference_mission"] = reference
        checks["reference_mission_realtime_factor_cpu"] = check(reference["realtime_factor_cpu"], ">= 60")
        checks["reference_mission_completed"] = check(float(reference["completed"]), ">= 1")
    return results, checks
