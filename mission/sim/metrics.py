"""Metrics of a simulated run: what the executive reported, measured against the truth the simulator kept (the
navigation error and the elements' true tracks by `mission.scoring`, as `auv score` does for `auv run`)."""

from __future__ import annotations

import copy
import math
from typing import Any

import numpy as np
from shapely.geometry import Polygon

from mission.agents.report import ExploreReport, InspectReport, SurveyReport
from mission.executive import ElementReport, ExecutionReport
from mission.frames import heading_of, invert, wrap_deg
from mission.language.models import Mission
from mission.onboard.report import run_fields
from mission.scoring import ElementSpan, navigation_errors, track_metrics
from mission.sim.vehicle import SimulatedVehicle
from mission.world.scene import Scene

DETECTION_RADIUS_M = 5.0  # a detection this close to a true object's centre is that object
MIN_OBJECT_HEIGHT_M = 1.0  # true objects at least this tall in the area must be detected


def _survey_truth(report: SurveyReport, rep: ElementReport, mission: Mission, scene: Scene) -> dict[str, Any]:
    """A survey's fields of `metrics.json`, its detections scored against the true objects: position errors,
    false alarms, missed objects."""
    item = copy.deepcopy(report.as_json())
    element = next((e for e in mission.route if e.id == rep.id), None)
    if element is None or element.survey is None:
        return item
    p = element.survey
    area = Polygon([(e, n) for n, e in p.area])
    for zone in p.exclude:
        area = area.difference(Polygon([(e, n) for n, e in zone]))
    truth = []
    for obj in scene.objects:
        c = obj.footprint.centroid
        seabed = scene.seabed.depth_at(c.y, c.x)
        truth.append((obj.id, c.y, c.x, seabed - obj.top_depth, area.contains(c)))
    found = set()
    detections = report.detections or []
    entries: list[dict[str, Any]] = item.get("detections", [])
    for det, entry in zip(detections, entries, strict=True):
        best = min(truth, key=lambda t: math.hypot(t[1] - det.north, t[2] - det.east), default=None)
        if best is not None:
            err = math.hypot(best[1] - det.north, best[2] - det.east)
            entry["true_object"] = best[0] if err <= DETECTION_RADIUS_M else None
            entry["position_error_m"] = round(err, 3) if err <= DETECTION_RADIUS_M else None
            if err <= DETECTION_RADIUS_M:
                found.add(best[0])
    item["false_alarms"] = sum(1 for e in entries if e.get("true_object") is None)
    item["missed"] = [t[0] for t in truth if t[4] and t[3] >= MIN_OBJECT_HEIGHT_M and t[0] not in found]
    return item


def _reference_truth(item: dict[str, Any], vehicle: SimulatedVehicle, scene: Scene) -> None:
    """Score every referencing attempt: the camera's estimated pose in the object frame against the truth."""
    truth = next((o for o in scene.objects if o.database == item.get("object") or o.id == item.get("object")), None)
    frames = dict(vehicle.log.frames)
    for attempt in item.get("attempts", []):
        T_world_cam_true = frames.get(attempt["time"])
        est = attempt.pop("T_object_cam", None)
        attempt.pop("T_world_cam_est", None)
        attempt.pop("T_world_object_est", None)
        if truth is None or T_world_cam_true is None or est is None:
            continue
        T_true = invert(truth.T_world_object) @ np.asarray(T_world_cam_true)
        T_est = np.asarray(est)
        attempt["position_error_m"] = round(float(np.linalg.norm(T_est[:3, 3] - T_true[:3, 3])), 4)
        cos = (np.trace(T_est[:3, :3].T @ T_true[:3, :3]) - 1.0) / 2.0
        attempt["rotation_error_deg"] = round(math.degrees(math.acos(min(1.0, max(-1.0, cos)))), 3)
        attempt["heading_error_deg"] = round(abs(wrap_deg(heading_of(T_est) - heading_of(T_true))), 3)
    item["recognised"] = any(a["recognised"] for a in item.get("attempts", []))


def _element_metrics(report: ExecutionReport, times: np.ndarray, north: np.ndarray, east: np.ndarray,
                     altitude: np.ndarray, vehicle: SimulatedVehicle, scene: Scene) -> list[dict[str, Any]]:
    mission = vehicle.mission
    out = []
    for rep in report.elements:
        item: dict[str, Any] = {"id": rep.id, "kind": rep.kind, "status": rep.status,
                                "duration_s": round(rep.duration_s, 2)}
        if rep.reason:
            item["reason"] = rep.reason
        goal = rep.planned_path[-1] if rep.kind == "transit" and rep.planned_path else None
        span = ElementSpan(rep.id, rep.start_time, rep.end_time, goal)
        item.update(track_metrics(span, times, north, east, altitude))
        details = rep.details
        if rep.kind == "survey" and isinstance(details, SurveyReport):
            item.update(_survey_truth(details, rep, mission, scene))
        elif rep.kind == "explore" and isinstance(details, ExploreReport):
            from mission.sim.explore_metrics import explore_truth

            element = next((e for e in mission.route if e.id == rep.id), None)
            safe = element.explore.safe_distance if element is not None and element.explore is not None else 0.0
            item.update(explore_truth(details, rep, report.knowledge, vehicle, scene, safe))
        elif rep.kind == "inspect" and isinstance(details, InspectReport):
            from mission.sim.inspect_metrics import inspect_truth

            item.update(inspect_truth(details, vehicle, scene))
        else:
            item.update(copy.deepcopy(details.as_json()))
        if rep.kind in ("reference", "inspect"):
            _reference_truth(item, vehicle, scene)
        out.append(item)
    return out


def run_metrics(mission_name: str, seed: int, report: ExecutionReport, vehicle: SimulatedVehicle, scene: Scene,
                wall_time_s: float) -> dict[str, Any]:
    """The `metrics.json` of a run (see the output contract in the README)."""
    rows = vehicle.log.rows
    arr = np.array([r[:14] for r in rows], dtype=float) if rows else np.zeros((0, 14))
    times, north, east, depth = arr[:, 0], arr[:, 1], arr[:, 2], arr[:, 3]
    fixes = vehicle.log.fixes
    return {
        **run_fields(mission_name, seed, report, wall_time_s, vehicle.distance_m, vehicle.energy_used_wh,
                     vehicle.mission.vehicle.energy_wh),
        "elements": _element_metrics(report, times, north, east, arr[:, 5], vehicle, scene),
        "safety_violations": report.violations,
        "seabed_contacts": vehicle.log.seabed_contacts,
        "navigation": {
            **navigation_errors(north, east, depth, arr[:, 6], arr[:, 7], arr[:, 8]),
            "usbl_fixes": sum(1 for f in fixes if f.used),
            "usbl_rejected": sum(1 for f in fixes if f.used and not f.accepted),
        },
    }
