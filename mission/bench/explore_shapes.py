"""The explore element on object shapes nobody tuned it to (issue 21 item 3, seed 002 §2.2.2): how much of each
object's true surface it observes within its budget, how close its own completeness figure comes to that, and
how long its next-best-view iterations take.

Four full simulations (`mission.sim.run.simulate`: MuJoCo scanner, USBL-aided dead reckoning, the agent acting on
its estimated state), each a 40 × 40 m multibeam survey that finds the object (the database lacks it), then one
`explore` element (next-best-view, the reference mission's weights):

* three objects of our own in `data/explore_shapes.yaml` — a 6.3 m tower with side arms, a low wide template with
  fittings, an L-shaped pipeline end structure — on gravel near 72 m, 12-minute budget, safe distance 5 m;
* the reference world's wellhead-x (`worlds/sps_field.yaml`), the reference mission's 15 minutes and 6 m.

Per shape: `surface_observed_percent` (the truth: `mission.sim.explore_metrics`), the agent's own
`coverage_estimate_percent` (`planners.nbv.completeness`, from its map and estimated poses only), their
difference, the NBV iteration time (mean, max), the element's duration and why it stopped.

Checks (all shapes): observed ≥ 90 %, |own − truth| ≤ 3 points, NBV iteration (completeness estimate, propose,
connect) ≤ 1 s at most, in CPU time: the shapes run in parallel processes on a machine that may be shared, so
wall time (reported beside it) says more about the load than about the planner. `--quick` runs the template
alone with a 5-minute budget (its checks then say what that short run reached).
"""

from __future__ import annotations

import os
import time
from pathlib import Path
from typing import Any

from mission.bench import check

DATA = Path(__file__).resolve().parent / "data"
REPO = Path(__file__).resolve().parents[2]


def _shapes() -> dict[str, dict[str, Any]]:
    """Per shape: the world, the object's position, and the element's budget and safe distance."""
    ours = str(DATA / "explore_shapes.yaml")
    return {
        "tower": {"world": ours, "at": (40.0, 40.0), "budget": "12min", "safe": 5, "home_depth": 40.0},
        "template": {"world": ours, "at": (40.0, 150.0), "budget": "12min", "safe": 5, "home_depth": 40.0},
        "plet": {"world": ours, "at": (150.0, 60.0), "budget": "12min", "safe": 5, "home_depth": 40.0},
        "wellhead-x": {"world": str(REPO / "worlds" / "sps_field.yaml"), "at": (215.0, 110.0), "budget": "15min",
                       "safe": 6, "home_depth": 30.0},
    }


def shape_mission(name: str, budget: str | None = None, seed: int = 5) -> dict[str, Any]:
    """The mission (as a YAML-shaped dict) that surveys around one shape and explores what it finds."""
    s = _shapes()[name]
    n, e = s["at"]
    area = [[n - 20, e - 20], [n - 20, e + 20], [n + 20, e + 20], [n + 20, e - 20]]
    return {
        "name": f"explore-{name}", "world": s["world"], "seed": seed,
        "home": {"north": n - 35, "east": e - 25, "depth": s["home_depth"]},
        "vehicle": {"cruise_speed": 1.5, "turn_radius": 6},
        "sensors": {"mbes": {"beams": 256, "swath_deg": 120, "max_range": 80, "rate_hz": 10},
                    "scanner": {"fov_deg": [60, 45], "max_range": 12, "rate_hz": 2},
                    "usbl": {"sigma": 1.5, "rate_hz": 0.5}, "dvl": {"drift_percent": 0.5}},
        "safety": {"geofence": [[n - 80, e - 80], [n - 80, e + 80], [n + 80, e + 80], [n + 80, e - 80]],
                   "max_depth": 120, "min_altitude": 1.5},
        "route": [
            {"id": "find", "survey": {"area": area, "sensor": "mbes", "altitude": 20},
             "actions": ["map", "detect_objects"]},
            {"id": "scan", "explore": {"object": "detected", "sensor": "scanner", "planner": "next-best-view",
                                       "weights": {"distance": 0.3, "frontier": 0.5, "contour": 0.2},
                                       "safe_distance": s["safe"], "budget": budget or s["budget"]}}],
    }


def run_shape(name: str, budget: str | None = None, seed: int = 5, out: Path | None = None) -> dict[str, Any]:
    """Simulate one shape's mission; the explore element's figures against the truth."""
    from mission.language.models import Mission
    from mission.sim.run import simulate

    t0 = time.perf_counter()
    result = simulate(Mission.model_validate(shape_mission(name, budget, seed)), out=out, plots=out is not None)
    m = result.metrics
    scan = next(e for e in m["elements"] if e["id"] == "scan")
    obj = scan["objects"][0] if scan.get("objects") else {}
    truth = obj.get("surface_observed_percent")
    own = obj.get("coverage_estimate_percent")
    it = scan.get("iteration_time_ms") or {}
    cpu = scan.get("iteration_cpu_ms") or {}
    return {
        "object": name, "true_object": obj.get("true_object"), "completed": m["completed"],
        "status": scan["status"], "budget": budget or _shapes()[name]["budget"],
        "duration_s": scan.get("duration_s"), "stop_reason": obj.get("stop_reason"), "views": scan.get("views"),
        "surface_observed_percent": truth, "own_estimate_percent": own,
        "difference_points": round(own - truth, 2) if own is not None and truth is not None else None,
        "map_surface_percent": obj.get("map_surface_percent"),
        "iteration_ms": {"mean": it.get("mean"), "max": it.get("max")},
        "iteration_cpu_ms": {"mean": cpu.get("mean"), "max": cpu.get("max")},
        "min_distance_to_object_m": scan.get("min_distance_to_object_m"),
        "safe_distance_breached": scan.get("safe_distance_breached"),
        "wall_s": round(time.perf_counter() - t0, 1)}


def run(quick: bool) -> tuple[dict[str, Any], dict[str, dict[str, Any]]]:
    from concurrent.futures import ProcessPoolExecutor

    names = ["template"] if quick else list(_shapes())
    with ProcessPoolExecutor(max_workers=min(len(names), os.cpu_count() or 1)) as pool:
        rows = list(pool.map(run_shape, names, ["5min" if quick else None] * len(names)))
    observed = [r["surface_observed_percent"] or 0.0 for r in rows]
    gaps = [abs(r["difference_points"]) if r["difference_points"] is not None else float("inf") for r in rows]
    iterations = [r["iteration_cpu_ms"]["max"] or float("inf") for r in rows]
    results = {"shapes": rows, "world": "mission/bench/data/explore_shapes.yaml and worlds/sps_field.yaml",
               "seed": 5}
    checks = {
        "min_surface_observed_percent": check(min(observed), ">= 90"),
        "max_estimate_error_points": check(max(gaps), "<= 3"),
        "max_nbv_iteration_cpu_s": check(round(max(iterations) / 1e3, 3), "<= 1.0"),
    }
    return results, checks
