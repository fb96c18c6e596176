"""The README's fault-campaign table from campaign folders (`auv simulate missions/fault_*.yaml --seeds 1-4 ...`).

    python docs/fault_campaign.py runs/fault_navigation runs/fault_battery runs/fault_multibeam

For each fault of each seeded run: the true navigation error at the fault's start, its peak within the window, and
60 s after its end; the safety monitors that tripped; the elements' outcomes; and how the run ended (true depth,
distance from home, inside the geofence).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
from shapely.geometry import Point, Polygon

from mission.events import read_events
from mission.language import load_mission
from mission.runfolder import read_csv


def rows(campaign: Path) -> list[str]:
    out = []
    for seed_dir in sorted(campaign.glob("seed-*"), key=lambda p: int(p.name[5:])):
        metrics = json.loads((seed_dir / "metrics.json").read_text())
        mission = load_mission(seed_dir / "mission.yaml", environment=False)
        t, _ = read_csv(seed_dir / "trajectory.csv", ("element",))
        err = np.hypot(t["north"] - t["north_est"], t["east"] - t["east_est"])
        fence = Polygon([(e, n) for n, e in mission.safety.geofence]) if mission.safety.geofence else None
        inside = fence is None or all(fence.contains(Point(e, n)) for n, e in zip(t["north"], t["east"], strict=True))
        home = float(np.hypot(t["north"][-1] - mission.home.north, t["east"][-1] - mission.home.east))
        monitors = ",".join(v["monitor"] for v in metrics["safety_violations"]) or "none"
        events = read_events(seed_dir / "events.jsonl")
        started = {e["fault"]: e["time"] for e in events if e["event"] == "fault_started"}
        for fault in mission.faults:
            w = fault.window
            end = w.end if w.end is not None else t["time"][-1]
            inside_w = (t["time"] >= w.start) & (t["time"] <= end)
            after = np.abs(t["time"] - (end + 60.0)).argmin()
            at = np.abs(t["time"] - w.start).argmin()
            survey = next((e for e in metrics["elements"] if e["kind"] == "survey"), None)
            extra = f"; survey coverage {survey['coverage_percent']:.0f} %, false alarms {survey['false_alarms']}, " \
                    f"missed {len(survey['missed'])}" if survey else ""
            out.append(
                f"| {fault.kind} | {metrics['seed']} | {started.get(fault.kind, float('nan')):.0f} | "
                f"{err[at]:.1f} / {err[inside_w].max():.1f} / {err[after]:.1f} | {monitors} | "
                f"{'completed' if metrics['completed'] else 'aborted' if metrics['aborted'] else 'not completed'}"
                f"{extra} | {t['depth'][-1]:.1f} m, {home:.1f} m from home, {'inside' if inside else 'OUTSIDE'} |")
    return out


if __name__ == "__main__":
    print("| fault | seed | started (s) | nav error at start / peak / end + 60 s (m) | monitors tripped | outcome |"
          " end: true depth, from home, fence |")
    print("|---|---|---|---|---|---|---|")
    for arg in sys.argv[1:]:
        print("\n".join(rows(Path(arg))))
