"""What a run knows without the truth: the `metrics.json` of `auv run`, in the shape `auv simulate` writes.

The keys that need the truth (`navigation`, each element's true track, `distance_m`) are added by `auv score`
(`mission.scoring`); until then `scored` is false and `distance_m` is the estimated track's length.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from mission.executive import ExecutionReport


def jsonable(value: Any) -> Any:
    """Agent details as JSON: dataclasses as dicts, arrays as lists, non-finite floats as None."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return jsonable(dataclasses.asdict(value))
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, (np.floating, float)):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


def element_items(report: ExecutionReport) -> list[dict[str, Any]]:
    """Each element's status, duration, reason and its agent's details."""
    items = []
    for rep in report.elements:
        item: dict[str, Any] = {"id": rep.id, "kind": rep.kind, "status": str(rep.status),
                                "duration_s": round(rep.duration_s, 2)}
        if rep.reason:
            item["reason"] = rep.reason
        details = jsonable(rep.details.as_json())
        if isinstance(details, dict):
            item.update(details)
        items.append(item)
    return items


def run_fields(mission_name: str, seed: int, report: ExecutionReport, wall_time_s: float, distance_m: float,
               energy_used_wh: float, capacity_wh: float) -> dict[str, Any]:
    """The head of every run's `metrics.json` (`auv simulate`'s and `auv run`'s): how the run ended and what it
    took."""
    mission_time = report.end_time - report.start_time
    return {
        "mission": mission_name,
        "seed": seed,
        "completed": report.completed,
        "aborted": report.aborted,
        "abort_reason": report.abort_reason or None,
        "link_lost": report.link_lost,
        "stopped": report.stopped,
        "paused_s": round(report.paused_s, 2),
        "mission_time_s": round(mission_time, 2),
        "wall_time_s": round(wall_time_s, 3),
        "realtime_factor": round(mission_time / wall_time_s, 1) if wall_time_s > 0 else None,
        "distance_m": round(distance_m, 2),
        "energy_wh": round(energy_used_wh, 2),
        "energy_remaining_percent": round(100.0 * (1.0 - energy_used_wh / capacity_wh), 2) if capacity_wh else None,
    }


def onboard_metrics(mission_name: str, seed: int, report: ExecutionReport, wall_time_s: float,
                    estimated_distance_m: float, energy_used_wh: float, capacity_wh: float) -> dict[str, Any]:
    """The `metrics.json` of an `auv run` (see the module docstring)."""
    return {
        **run_fields(mission_name, seed, report, wall_time_s, estimated_distance_m, energy_used_wh, capacity_wh),
        "elements": element_items(report),
        "safety_violations": jsonable(report.violations),
        "seabed_contacts": None,
        "navigation": {},
        "scored": False,
    }
