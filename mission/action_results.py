"""What each route element's actions produced, for the `actions` block of its `metrics.json` entry: the map file
written (`map`), the detections (`detect_objects`), the photographs taken (`photograph`), the stereo pairs
recorded and their folder (`record`, `model`), and for an explore element the sensor it flew with.

The block has one key per action the element asked for, so a reader sees at once whether each one did its work:

    {"map": "maps/survey-1.npz", "detect_objects": 2, "photos": 10, "record": "stereo/look", "recorded_pairs": 240}
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

from mission.agents.report import ExploreReport, InspectReport, SurveyReport
from mission.language.actions import explore_sensor
from mission.language.models import Explore, Mission, RouteElement

if TYPE_CHECKING:
    from mission.executive import ElementReport, ExecutionReport


def mapped_elements(mission: Mission) -> set[str]:
    """The ids of the route elements whose maps go into the run folder (those with the `map` action)."""
    return {e.id for e in mission.route if "map" in e.actions}


def _photos(rep: ElementReport) -> int:
    details = rep.details
    if isinstance(details, InspectReport):
        return len(details.photos)
    if isinstance(details, ExploreReport):
        return len(details.photo_times or [])
    return 0


def element_actions(element: RouteElement, rep: ElementReport, maps_written: Iterable[str]) -> dict[str, Any]:
    """The `actions` block of one element that ran (see the module docstring)."""
    out: dict[str, Any] = {}
    for action in element.actions:
        if action == "map":
            out["map"] = f"maps/{element.id}.npz" if element.id in set(maps_written) else None
        elif action == "detect_objects":
            details = rep.details
            out["detect_objects"] = len(details.detections or []) if isinstance(details, SurveyReport) else 0
        elif action == "photograph":
            out["photos"] = _photos(rep)
        elif action in ("record", "model"):
            out[action] = f"stereo/{element.id}"
            out["recorded_pairs"] = rep.recorded_pairs or 0
    if isinstance(element.params, Explore):
        out["sensor"] = explore_sensor(element.params)
    return out


def add_action_results(metrics: dict[str, Any], mission: Mission, report: ExecutionReport,
                       maps_written: Iterable[str]) -> None:
    """Give every element entry of `metrics["elements"]` its `actions` block."""
    elements = {e.id: e for e in mission.route}
    reports = {r.id: r for r in report.elements}
    written = set(maps_written)
    for item in metrics.get("elements", []):
        element, rep = elements.get(item.get("id", "")), reports.get(item.get("id", ""))
        if element is not None and rep is not None:
            item["actions"] = element_actions(element, rep, written)
