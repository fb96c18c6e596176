"""The route as a fixed plan: the legs an autopilot can fly without the onboard executive.

Transit and survey elements are plannable before the vehicle dives: a transit is one waypoint (home, or its
point) and a survey is the meander `planners.coverage.meander` gives for the area, the multibeam's swath and the
overlap, started where the previous leg ends (as the survey agent plans it). Explore, inspect and reference decide
their motion from what the sensors see, so only the onboard executive can fly them: `plan_legs(strict=True)`
refuses them by name, with the line of the mission file where they stand.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mission.errors import Diagnostic, MissionError
from mission.language.models import Mission, RouteElement
from planners.coverage import line_spacing, meander

PLANNABLE = ("transit", "survey")


@dataclass(frozen=True)
class Leg:
    """One plannable element: its waypoints (north, east) in metres, and the vertical reference it holds.

    Exactly one of `depth` (metres below the surface) and `altitude` (metres above the seabed) is set.
    `speed` is the element's speed (m/s), the vehicle's cruise speed when the element gives none.
    """

    element: str
    kind: str
    points_ne: tuple[tuple[float, float], ...]
    depth: float | None
    altitude: float | None
    speed: float


def _locate(mission: Mission, path: tuple[str | int, ...], message: str) -> Diagnostic:
    source = mission.source
    if source and Path(source).is_file():
        from mission.language.source import read_yaml

        return read_yaml(Path(source)).diagnostic(path, message)
    return Diagnostic(source or f"mission '{mission.name}'", 1, 1, message)


def adaptive_elements(mission: Mission) -> list[tuple[int, RouteElement]]:
    """The route elements (with their index) that only the onboard executive can fly."""
    return [(i, el) for i, el in enumerate(mission.route) if el.kind not in PLANNABLE]


def refuse_adaptive(mission: Mission, target: str) -> None:
    """Raise MissionError, located at the first adaptive element, naming every one that `target` cannot carry."""
    found = adaptive_elements(mission)
    if found:
        names = ", ".join(f"'{el.id}' ({el.kind})" for _, el in found)
        many = len(found) > 1
        raise MissionError([_locate(mission, ("route", found[0][0]),
                                    f"route element{'s' if many else ''} {names} {'are' if many else 'is'} adaptive: "
                                    f"only the onboard executive can fly {'them' if many else 'it'}, so {target} "
                                    f"cannot carry {'them' if many else 'it'} (plannable: {', '.join(PLANNABLE)})")])


def plan_legs(mission: Mission, *, strict: bool = True, target: str = "fixed plan") -> list[Leg]:
    """The legs of the route's plannable elements in order, from home.

    With `strict`, an adaptive element is an error (`refuse_adaptive`); without, it is skipped and the next leg
    starts where the last plannable one ended.
    """
    if strict:
        refuse_adaptive(mission, target)
    here = (mission.home.north, mission.home.east)
    depth: float | None = mission.home.depth
    legs: list[Leg] = []
    for el in mission.route:
        speed_given = getattr(el.params, "speed", None)
        speed = float(speed_given or mission.vehicle.cruise_speed)
        if el.transit is not None:
            t = el.transit
            to = (mission.home.north, mission.home.east) if t.to == "home" else (t.to.north, t.to.east)
            points: tuple[tuple[float, float], ...] = ((float(to[0]), float(to[1])),)
            if t.altitude is not None:
                legs.append(Leg(el.id, "transit", points, None, float(t.altitude), speed))
                depth = None
            else:
                depth = float(t.depth) if t.depth is not None else (depth if depth is not None else 0.0)
                legs.append(Leg(el.id, "transit", points, depth, None, speed))
            here = points[-1]
        elif el.survey is not None:
            s, mbes = el.survey, mission.sensors.mbes
            swath = mbes.swath_deg if mbes is not None else 120.0
            plan = meander(s.area, s.exclude, spacing=line_spacing(s.altitude, swath, s.overlap), heading=s.heading,
                           turn_radius=mission.vehicle.turn_radius, start=here)
            wps = np.asarray(plan.waypoints, float)
            points = tuple((float(n), float(e)) for n, e in wps)
            legs.append(Leg(el.id, "survey", points, None, float(s.altitude), speed))
            here, depth = points[-1], None
    return legs
