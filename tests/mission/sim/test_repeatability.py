"""A seeded run repeats exactly, plug-in workers and all: the simulator charges each plug-in call a modelled
latency, never the machine's time (what the call's CPU took varies with the machine and its load)."""

from __future__ import annotations

import json
from pathlib import Path

from mission.language import load_mission
from mission.sim.run import simulate

MISSION = Path(__file__).resolve().parents[3] / "missions" / "manifold_referencing.yaml"
WALL_FIELDS = ("wall_time_s", "realtime_factor", "plugins")


def _without_wall_times(metrics: dict) -> str:
    kept = {k: v for k, v in metrics.items() if k not in WALL_FIELDS}
    for element in kept["elements"]:
        for attempt in element.get("attempts", []):
            attempt.pop("time_ms", None)
    return json.dumps(kept, sort_keys=True)  # as text: NaN (an attempt's residual) equals itself


def test_two_runs_of_a_seed_with_a_referencing_plugin_give_the_same_trajectory_and_metrics(tmp_path):
    runs = [simulate(load_mission(MISSION), seed=3, out=tmp_path / f"run{i}", plots=False) for i in (1, 2)]
    assert runs[0].metrics["plugins"]["referencing"]["calls"] >= 3  # the plug-in really ran, in its worker
    first, second = ((tmp_path / f"run{i}" / "trajectory.csv").read_bytes() for i in (1, 2))
    assert first == second
    assert _without_wall_times(runs[0].metrics) == _without_wall_times(runs[1].metrics)
