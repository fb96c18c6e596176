"""Simulation speed: a one-hour transit-only mission with plots off must run at >= 720x real time (<= 5 s).

There is no external simulator to anchor against here; the anchor is real time itself (the executive running
the same mission on a vehicle), so the ratio reported is the real-time factor. The mission is
`missions/transit_hour.yaml`; repeated runs give the median.
"""

from __future__ import annotations

import statistics
from typing import Any

from mission.bench import REPO, check


def run(quick: bool) -> tuple[dict[str, Any], dict[str, dict[str, Any]]]:
    from mission import load_mission
    from mission.sim.run import simulate

    mission = load_mission(REPO / "missions" / "transit_hour.yaml")
    repeats = 2 if quick else 7
    walls, steps = [], 0
    mission_time = 0.0
    for seed in range(repeats):
        result = simulate(mission, seed=seed, plots=False)
        walls.append(result.metrics["wall_time_s"])
        mission_time = result.metrics["mission_time_s"]
        steps = len(result.vehicle.log.rows)
    wall = statistics.median(walls)
    results = {
        "mission": "missions/transit_hour.yaml",
        "mission_time_s": mission_time,
        "control_steps": steps,
        "wall_time_s": {"median": wall, "min": min(walls), "max": max(walls), "runs": len(walls)},
        "realtime_factor_vs_anchor": round(mission_time / wall, 1),
        "us_per_step": round(1e6 * wall / steps, 1),
    }
    checks = {
        "one_hour_mission_wall_time_s": check(round(wall, 3), "<= 5"),
        "realtime_factor": check(round(mission_time / wall, 1), ">= 720"),
    }
    return results, checks
