"""Cross-checks of speeds and time: a speed the vehicle cannot reach, a survey with too many lines, and a route
that cannot fit in `safety.max_duration`.

The duration is a rough lower estimate: straight transit legs and survey tracks at the speeds the mission asks
for (explorations count their budgets; inspections and referencing, which the route does not size, count nothing).
A route estimated longer than `max_duration` is a warning: the mission is legal, but it will abort when time runs
out (some missions do that on purpose).
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

from shapely.geometry import Polygon as ShapelyPolygon

from mission.errors import Diagnostic
from mission.language.limits import MAX_SURVEY_LINES
from mission.language.models import Explore, Survey, Transit
from mission.language.source import Located
from planners.coverage import line_spacing

if TYPE_CHECKING:
    from mission.language.checks import Parts


@dataclasses.dataclass
class _Walk:
    """Where the estimate stands: the vehicle's last known point and the seconds used so far."""

    here: tuple[float, float] | None
    depth: float
    seconds: float = 0.0
    metres: float = 0.0


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
    """Speeds against `vehicle.max_speed`, survey line counts, and the route's rough duration against
    `safety.max_duration`."""
    out = _speed_checks(doc, parts)
    vehicle, safety, home = parts.vehicle, parts.safety, parts.home
    mbes = parts.sensors.mbes if parts.sensors is not None else None
    walk = _Walk((home.north, home.east) if home is not None else None, home.depth if home is not None else 0.0)
    cruise = vehicle.cruise_speed if vehicle is not None else None
    vertical = vehicle.max_vertical_speed if vehicle is not None else None
    for i, element in parts.route:
        p = element.params
        speed = getattr(p, "speed", None) or cruise
        if isinstance(p, Transit):
            goal = (home.north, home.east) if isinstance(p.to, str) and home is not None else (
                None if isinstance(p.to, str) else (p.to.north, p.to.east))
            if walk.here is not None and goal is not None and speed:
                leg = math.dist(walk.here, goal)
                walk.metres += leg
                walk.seconds += leg / speed
            if p.depth is not None and vertical:
                walk.seconds += abs(p.depth - walk.depth) / vertical
                walk.depth = p.depth
            walk.here = goal
        elif isinstance(p, Survey) and mbes is not None:
            lines, track = _survey_lines(p, mbes.swath_deg)
            if lines > MAX_SURVEY_LINES:
                out.append(doc.diagnostic(("route", i, "survey", "altitude"),
                                          f"the survey '{element.id}' would need about {lines:.3g} lines (at most "
                                          f"{MAX_SURVEY_LINES:,}); fly higher, overlap less or survey a smaller area"))
            if speed:
                walk.metres += track
                walk.seconds += track / speed
            walk.here = None
        elif isinstance(p, Explore):
            walk.seconds += p.budget
            walk.here = None
        else:
            walk.here = None
    if safety is not None and walk.seconds > safety.max_duration:
        d = doc.diagnostic(("safety", "max_duration"),
                           f"the route needs at least about {walk.seconds:.0f} s ({walk.metres:.0f} m at the speeds "
                           f"asked, with exploration budgets) but safety.max_duration is {safety.max_duration:.0f} s: "
                           "the mission will abort when its time runs out")
        out.append(dataclasses.replace(d, warning=True))
    return out
