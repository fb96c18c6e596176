"""Cross-checks of speeds and time: a speed the vehicle cannot reach, a survey with too many lines, and a route
whose estimate (`mission.estimate`) cannot fit in `safety.max_duration` (a warning: the mission is legal, but it
will abort when time runs out; some missions do that on purpose).
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

from shapely.geometry import Polygon as ShapelyPolygon

from mission.errors import Diagnostic
from mission.language.limits import MAX_SURVEY_LINES
from mission.language.models import Mission, Survey, Transit
from mission.language.source import Located
from planners.coverage import line_spacing

if TYPE_CHECKING:
    from mission.language.checks import Parts


def _speed_checks(doc: Located, parts: Parts) -> list[Diagnostic]:
    vehicle = parts.vehicle
    if vehicle is None:
        return []
    out = []
    for i, element in parts.route:
        p = element.params
        speed = getattr(p, "speed", None)
        if isinstance(p, Transit | Survey) and speed is not None and speed > vehicle.max_speed:
            out.append(doc.diagnostic(("route", i, element.kind, "speed"),
                                      f"speed {speed:g} m/s of '{element.id}' exceeds vehicle.max_speed "
                                      f"{vehicle.max_speed:g} m/s"))
    return out


def _survey_lines(survey: Survey, swath_deg: float) -> tuple[float, float]:
    """(number of lines, track length in metres) of a meander over the survey area, roughly."""
    spacing = line_spacing(survey.altitude, swath_deg, survey.overlap)
    area = ShapelyPolygon([(e, n) for n, e in survey.area])
    e0, n0, e1, n1 = area.bounds
    across = min(e1 - e0, n1 - n0)
    lines = across / spacing + 1.0
    return lines, area.area / spacing + across


def check_timing(doc: Located, parts: Parts) -> list[Diagnostic]:
    """Speeds against `vehicle.max_speed` and survey line counts (the route's duration against
    `safety.max_duration` is `duration_warning`, on the whole mission)."""
    out = _speed_checks(doc, parts)
    mbes = parts.sensors.mbes if parts.sensors is not None else None
    for i, element in parts.route:
        p = element.params
        if isinstance(p, Survey) and mbes is not None:
            lines, _ = _survey_lines(p, mbes.swath_deg)
            if lines > MAX_SURVEY_LINES:
                out.append(doc.diagnostic(("route", i, "survey", "altitude"),
                                          f"the survey '{element.id}' would need about {lines:.3g} lines (at most "
                                          f"{MAX_SURVEY_LINES:,}); fly higher, overlap less or survey a smaller area"))
    return out


def duration_warning(doc: Located, mission: Mission) -> list[Diagnostic]:
    """A warning when the route's estimate (`mission.estimate`, surveys sized from their area rather than planned,
    so that validation stays fast) exceeds `safety.max_duration`: legal, but the mission will abort when its time
    runs out (some missions do that on purpose)."""
    from mission.estimate import estimate_mission

    estimate = estimate_mission(mission, plan_surveys=False)
    if estimate.duration_s <= mission.safety.max_duration:
        return []
    d = doc.diagnostic(("safety", "max_duration"),
                       f"the route is estimated at {estimate.duration_s:.0f} s ({estimate.distance_m:.0f} m; "
                       f"`auv plan` details it) but safety.max_duration is {mission.safety.max_duration:.0f} s: the "
                       "mission will abort when its time runs out")
    return [dataclasses.replace(d, warning=True)]
