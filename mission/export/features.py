"""What a mission or a run shows on a chart, as geometry in the local frame with properties: one collection that
the GeoJSON and KML writers both draw (`mission.export.geojson`, `mission.export.kml`).

From a mission: the geofence, the survey areas and their no-go zones, the planned paths of the plannable elements
(`mission.export.plan`), the database objects and home. From a run folder, besides its mission: the true and the
estimated tracks, the objects the survey detected, the photos (as points, with their files) and the safety events,
each event placed on the estimated track at its time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from mission.export.plan import plan_legs
from mission.language.models import Mission

Geometry = Literal["Point", "LineString", "Polygon"]
Property = str | float | int | bool | None
SAFETY_EVENTS = ("safety_violation", "abort", "stopped", "link_lost", "element_failed", "agent_fault")


@dataclass(frozen=True)
class Feature:
    """A point, a polyline or a polygon (outer ring, then holes) in local (north, east) metres."""

    layer: str
    name: str
    geometry: Geometry
    rings_ne: tuple[np.ndarray, ...]
    properties: dict[str, Property] = field(default_factory=dict)


def _poly(layer: str, name: str, ring: Any, **props: Property) -> Feature:
    return Feature(layer, name, "Polygon", (np.asarray(ring, float).reshape(-1, 2),), dict(props))


def _point(layer: str, name: str, north: float, east: float, **props: Property) -> Feature:
    return Feature(layer, name, "Point", (np.array([[north, east]], float),), dict(props))


def mission_features(mission: Mission) -> list[Feature]:
    """The mission's areas, planned paths, database objects and home."""
    out: list[Feature] = []
    if mission.safety.geofence is not None:
        out.append(_poly("geofence", "geofence", mission.safety.geofence, max_depth=mission.safety.max_depth))
    for el in mission.route:
        if el.survey is None:
            continue
        out.append(_poly("survey_areas", el.id, el.survey.area, element=el.id, altitude=el.survey.altitude,
                         overlap=el.survey.overlap))
        for k, zone in enumerate(el.survey.exclude):
            out.append(_poly("no_go_zones", f"{el.id} no-go {k + 1}", zone, element=el.id))
    start = (mission.home.north, mission.home.east)
    for leg in plan_legs(mission, strict=False):
        line = np.asarray((start, *leg.points_ne), float)
        out.append(Feature("planned_paths", leg.element, "LineString", (line,),
                           {"element": leg.element, "kind": leg.kind, "depth": leg.depth, "altitude": leg.altitude,
                            "speed": leg.speed}))
        start = leg.points_ne[-1]
    for obj in mission.objects:
        out.append(_point("objects", obj.id, obj.pose.north, obj.pose.east, id=obj.id, depth=obj.pose.depth,
                          heading=obj.pose.heading, description=obj.description))
    out.append(_point("home", "home", mission.home.north, mission.home.east, depth=mission.home.depth))
    return out


def _track(layer: str, name: str, north: np.ndarray, east: np.ndarray) -> list[Feature]:
    keep = np.isfinite(north) & np.isfinite(east)
    if keep.sum() < 2:  # `auv run` folders have no truth until `auv score` fills it
        return []
    line = np.column_stack([north[keep], east[keep]])
    return [Feature(layer, name, "LineString", (line,), {"points": int(keep.sum())})]


def _at(time: np.ndarray, north: np.ndarray, east: np.ndarray, t: float) -> tuple[float, float]:
    keep = np.isfinite(north) & np.isfinite(east)
    return (float(np.interp(t, time[keep], north[keep])), float(np.interp(t, time[keep], east[keep])))


def _plain(value: Any) -> Property:
    if isinstance(value, float) and not math.isfinite(value):
        return None  # GeoJSON is JSON: no NaN
    if isinstance(value, (str, int, float, bool)) or value is None:
        return value
    return str(value)


def run_features(mission: Mission, trajectory: dict[str, np.ndarray], events: list[dict[str, Any]],
                 metrics: dict[str, Any]) -> list[Feature]:
    """A run's tracks, detections, photos and safety events (see the module docstring), after its mission's."""
    out = mission_features(mission)
    t = trajectory["time"]
    out += _track("true_track", "true track", trajectory["north"], trajectory["east"])
    out += _track("estimated_track", "estimated track", trajectory["north_est"], trajectory["east_est"])
    for det in _detections(metrics):
        out.append(_point("detections", str(det.get("id", "detection")), float(det["north"]), float(det["east"]),
                          **{k: _plain(v) for k, v in det.items() if k not in ("north", "east")}))
    for ev in events:
        name = str(ev.get("event", ""))
        if name != "photo" and name not in SAFETY_EVENTS:
            continue
        n, e = _at(t, trajectory["north_est"], trajectory["east_est"], float(ev.get("time", 0.0)))
        layer = "photos" if name == "photo" else "safety_events"
        label = str(ev.get("file", name)) if name == "photo" else name
        out.append(_point(layer, label, n, e, **{k: _plain(v) for k, v in ev.items()}))
    return out


def _detections(metrics: dict[str, Any]) -> list[dict[str, Any]]:
    """Detected objects listed in metrics.json (each with at least north and east)."""
    found: list[dict[str, Any]] = []

    def visit(node: Any) -> None:
        if isinstance(node, dict):
            for key, value in node.items():
                if key in ("detections", "detected") and isinstance(value, list):
                    found.extend(d for d in value if isinstance(d, dict) and "north" in d and "east" in d)
                else:
                    visit(value)
        elif isinstance(node, list):
            for item in node:
                visit(item)

    visit(metrics)
    return found
