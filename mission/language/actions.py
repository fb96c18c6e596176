"""What each route-element kind can do (seed 002 §1: a route element is a motion, an object and actions), and the
loader's checks of a route's `actions:` and of `explore.sensor` against it.

| action           | kinds that take it                                   | sensor it needs |
|------------------|------------------------------------------------------|-----------------|
| `map`            | survey, explore                                      |                 |
| `detect_objects` | survey                                               |                 |
| `photograph`     | inspect (required there: photographs are its product), explore with `planner: rrt-photo` | stereo |
| `record`         | every kind                                           | stereo          |
| `model`          | explore                                              | stereo          |

An explore element flies with the sensor its planner uses: `next-best-view` scans with the 3-D scanner,
`rrt-photo` photographs with the stereo camera (`EXPLORE_SENSORS`); `explore.sensor` names it, and any other is
refused rather than silently replaced. `goal: reconstruct` plans views for the stereo camera too: it needs
`planner: next-best-view`, a stereo camera, and a useful range (`planners.nbv.USEFUL_RANGE_SHARE` of the
camera's) beyond the planning distance (`safe_distance` + `EXPLORE_NAV_MARGIN_M`), or no view could ever see the
object well (`check_explore_goal`).
"""

from __future__ import annotations

from collections.abc import Mapping

from mission.errors import Diagnostic
from mission.language.models import ELEMENT_KINDS, Explore, RouteElement, Sensors
from mission.language.source import Located, PathKey

ACTION_KINDS: Mapping[str, tuple[str, ...]] = {
    "map": ("survey", "explore"),
    "detect_objects": ("survey",),
    "photograph": ("inspect", "explore"),
    "record": ELEMENT_KINDS,
    "model": ("explore",),
}
ACTION_SENSORS: Mapping[str, str] = {"photograph": "stereo", "record": "stereo", "model": "stereo"}
REQUIRED_ACTIONS: Mapping[str, tuple[tuple[str, str], ...]] = {  # kind: (action, why), ...
    "inspect": (("photograph", "photographs are what an inspection makes"),)}
EXPLORE_SENSORS: Mapping[str, tuple[str, ...]] = {"next-best-view": ("scanner",), "rrt-photo": ("stereo",)}
PHOTOGRAPHING_PLANNERS = ("rrt-photo",)  # explore planners that take photographs (the others scan)
EXPLORE_NAV_MARGIN_M = 1.0
"""What next-best-view exploration adds to `safe_distance` for the navigation error between its map and the truth
(its planning distance; `mission.agents.explore.NAV_MARGIN_M`)."""


def kinds_taking(action: str) -> tuple[str, ...]:
    """The element kinds an action applies to.

    >>> kinds_taking("map")
    ('survey', 'explore')
    """
    return tuple(ACTION_KINDS[action])


def explore_sensor(p: Explore) -> str:
    """The sensor an explore element flies with: the one it names, which the loader has checked its planner uses."""
    return p.sensor


def _action_problem(element: RouteElement, action: str, sensors: Sensors | None) -> str:
    kinds = kinds_taking(action)
    if element.kind not in kinds:
        return (f"action '{action}' does not apply to a {element.kind} element ('{element.id}'); "
                f"it applies to: {', '.join(kinds)}")
    p = element.params
    if action == "photograph" and isinstance(p, Explore) and p.planner not in PHOTOGRAPHING_PLANNERS:
        return (f"action 'photograph' of explore element '{element.id}' needs `planner: "
                f"{' or '.join(PHOTOGRAPHING_PLANNERS)}` (next-best-view scans; it takes no photographs)")
    need = ACTION_SENSORS.get(action)
    if need and sensors is not None and getattr(sensors, need) is None:
        return (f"action '{action}' of '{element.id}' needs the '{need}' sensor, which `sensors` does not "
                "configure")
    return ""


def check_actions(doc: Located, route: list[tuple[int, RouteElement]], sensors: Sensors | None
                  ) -> list[Diagnostic]:
    """Every action a route element's kind does not take or its sensors cannot do, a duplicated action, a
    required action left out, and an explore sensor its planner does not use."""
    out: list[Diagnostic] = []
    for i, element in route:
        seen: set[str] = set()
        for k, action in enumerate(element.actions):
            where: PathKey = ("route", i, "actions", k)
            if action in seen:
                out.append(doc.diagnostic(where, f"action '{action}' is listed twice in '{element.id}'"))
            seen.add(action)
            problem = _action_problem(element, action, sensors)
            if problem:
                out.append(doc.diagnostic(where, problem))
        for needed, why in REQUIRED_ACTIONS.get(element.kind, ()):
            if needed not in element.actions:
                out.append(doc.diagnostic(("route", i, element.kind), f"{element.kind} element '{element.id}' "
                                          f"must list `{needed}` in its actions: {why}"))
        p = element.params
        if isinstance(p, Explore):
            out.extend(check_explore_goal(doc, i, element.id, p, sensors))
        if isinstance(p, Explore) and p.sensor not in EXPLORE_SENSORS[p.planner]:
            uses = " or ".join(EXPLORE_SENSORS[p.planner])
            out.append(doc.diagnostic(("route", i, "explore", "sensor"), f"explore planner '{p.planner}' flies "
                                      f"with the {uses}, not the {p.sensor} (set `sensor: {uses}`)"))
    return out


def check_explore_goal(doc: Located, i: int, element_id: str, p: Explore, sensors: Sensors | None
                       ) -> list[Diagnostic]:
    """The `reconstruct` goal without next-best-view, without a stereo camera, or with a camera whose useful
    range does not reach past the planning distance."""
    if p.goal != "reconstruct":
        return []
    where: PathKey = ("route", i, "explore", "goal")
    if p.planner != "next-best-view":
        return [doc.diagnostic(where, f"explore goal 'reconstruct' of '{element_id}' needs `planner: "
                               f"next-best-view` (it plans the views; '{p.planner}' does not)")]
    if sensors is None:
        return []
    if sensors.stereo is None:
        return [doc.diagnostic(where, f"explore goal 'reconstruct' of '{element_id}' needs a stereo camera, "
                               "which `sensors` does not configure (add `sensors.stereo`)")]
    from planners.nbv import USEFUL_RANGE_SHARE

    useful = USEFUL_RANGE_SHARE * sensors.stereo.max_range
    planning = p.safe_distance + EXPLORE_NAV_MARGIN_M
    if planning >= useful:
        return [doc.diagnostic(where, f"explore goal 'reconstruct' of '{element_id}': the stereo camera's useful "
                               f"range ({USEFUL_RANGE_SHARE:g} × max_range {sensors.stereo.max_range:g} m = "
                               f"{useful:g} m) does not reach past the planning distance (safe_distance "
                               f"{p.safe_distance:g} m + {EXPLORE_NAV_MARGIN_M:g} m margin = {planning:g} m): "
                               "no view could see the object well; lower safe_distance or raise the range")]
    return []
