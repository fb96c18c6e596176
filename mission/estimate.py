"""Estimates before the dive (issue 23, item 4): per route element and in total, the distance, duration and energy
a mission will take, and the coverage its surveys plan, from the planners and the vehicle model, without
simulating.

The estimate walks the route from the home position, element by element, keeping the planned position and depth:
- `transit`: the straight leg at the element's speed (over ground: the water current along the leg added), the
  acceleration from rest, the final approach that slows down over three capture radii (`TransitAgent`), and the
  vertical change at the vehicle's vertical speed, which goes on during the leg;
- `survey`: the survey agent's own plan (`planners.coverage.meander` from where the vehicle will be), flown at the
  survey speed, and the swath coverage of its lines (`planners.coverage.coverage_fraction`);
- `explore`, `inspect`, `reference`: adaptive elements, whose length depends on what the vehicle finds. They are
  estimated from their budgets: the explore element's `budget`, the inspection's search budget plus a working
  time per target, the referencing search plus its fine views; their distance at the work speed. The `basis`
  field says which figures come from a plan and which from a budget.

Energy is the vehicle model's (`mission.sim.vehicle`): hotel power all the time, propulsion power times the cube
of speed over cruise speed while moving. The seabed and the current come from a `Chart` of the site when one is
given (`auv plan` charts the mission's world).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

from mission.language.models import Explore, Inspect, Mission, Pose, Reference, RouteElement, Survey, Transit
from mission.vehicle import STATION_KEEPING_SPEED_M_S

DEPTH_GAIN = 0.4  # (m/s) per m: the autopilot's depth loop (`mission.sim.kinematics`)
DEPTH_TOLERANCE_M = 1.0  # a vertical target counts as reached within this band (`TransitAgent`)
SLOW_SPEED_M_S = 0.3  # the slowest final-approach speed (`TransitAgent`)
WORK_FRACTION_MOVING = 0.5  # share of an adaptive element's time spent moving at the work speed
TARGET_WORK_S = 60.0  # an inspected target: fly to its viewpoint, settle, re-reference, photograph
REFERENCE_FINE_S = 45.0  # a referencing element after its set is found: settle over it, fine views, fusion


@dataclass(frozen=True)
class ElementEstimate:
    id: str
    kind: str
    distance_m: float
    duration_s: float
    energy_wh: float
    basis: str  # "plan" (from the planners) or "budget" (an adaptive element's budget)
    coverage_percent: float | None = None
    path: tuple[tuple[float, float], ...] = field(default=(), repr=False)  # planned (north, east), if planned

    def as_json(self) -> dict[str, Any]:
        out = asdict(self)
        out.pop("path")
        return {k: (round(v, 1) if isinstance(v, float) else v) for k, v in out.items() if v is not None}


@dataclass(frozen=True)
class MissionEstimate:
    elements: list[ElementEstimate]
    warnings: list[str] = field(default_factory=list)

    @property
    def distance_m(self) -> float:
        return sum(e.distance_m for e in self.elements)

    @property
    def duration_s(self) -> float:
        return sum(e.duration_s for e in self.elements)

    @property
    def energy_wh(self) -> float:
        return sum(e.energy_wh for e in self.elements)

    def as_json(self) -> dict[str, Any]:
        return {"elements": [e.as_json() for e in self.elements],
                "total": {"distance_m": round(self.distance_m, 1), "duration_s": round(self.duration_s, 1),
                          "energy_wh": round(self.energy_wh, 1)},
                "warnings": self.warnings}


@dataclass
class _Where:
    """Where the vehicle will be when an element starts."""

    north: float
    east: float
    depth: float


@dataclass
class Chart:
    """What is known of the site before the dive: the seabed depth (`depth_at(north, east)`, metres) and the water
    current (north, east, m/s). `auv plan` charts the mission's world (`mission.world.chart`); the executive has
    none, and then altitudes keep the depth the vehicle has."""

    depth_at: Callable[[float, float], float] | None = None
    current: tuple[float, float] = (0.0, 0.0)


class _Site:
    """The chart, and the survey plans made so far (a plan depends on where the survey begins only through its
    first line)."""

    def __init__(self, chart: Chart | None, plan_surveys: bool = True):
        chart = chart or Chart()
        self.plan_surveys = plan_surveys
        self.plans: dict[str, Any] = {}
        self.seabed_depth = chart.depth_at
        self.current = chart.current

    def depth_at_altitude(self, north: float, east: float, altitude: float) -> float | None:
        if self.seabed_depth is None:
            return None
        return max(float(self.seabed_depth(north, east)) - altitude, 0.0)


class RouteEstimator:
    """Estimates of route elements flown in a given order from a given position (the strategic level re-plans
    with it; `estimate_mission` gives the whole route's)."""

    def __init__(self, mission: Mission, chart: Chart | None = None, plan_surveys: bool = True):
        self.mission = mission
        self.site = _Site(chart, plan_surveys)

    def route(self, elements: Sequence[RouteElement], north: float, east: float,
              depth: float) -> list[ElementEstimate]:
        here = _Where(north, east, depth)
        return [_element(self.mission, self.site, element, here) for element in elements]

    def end_of(self, element: RouteElement, north: float, east: float, depth: float) -> tuple[float, float, float]:
        """Where the vehicle will be after `element`, begun at (north, east, depth)."""
        here = _Where(north, east, depth)
        _element(self.mission, self.site, element, here)
        return here.north, here.east, here.depth


def estimate_mission(mission: Mission, route: Sequence[RouteElement] | None = None,
                     estimator: RouteEstimator | None = None, chart: Chart | None = None,
                     plan_surveys: bool = True) -> MissionEstimate:
    """The estimate of every element of `route` (default: the mission's, as listed) from the home position, and
    warnings against `max_duration` and the energy reserve. Without `plan_surveys` a survey's track is sized from
    its area (`survey_track_m`), in microseconds instead of the coverage planner's second."""
    home = mission.home
    estimator = estimator or RouteEstimator(mission, chart, plan_surveys)
    estimate = MissionEstimate(estimator.route(mission.route if route is None else route,
                                               home.north, home.east, home.depth))
    safety = mission.safety
    if estimate.duration_s > safety.max_duration:
        estimate.warnings.append(f"the estimated duration {estimate.duration_s / 60:.0f} min exceeds max_duration "
                                 f"{safety.max_duration / 60:.0f} min")
    usable = mission.vehicle.energy_wh * (1.0 - _reserve_fraction(mission))
    if estimate.energy_wh > usable:
        estimate.warnings.append(f"the estimated energy {estimate.energy_wh:.0f} Wh exceeds the {usable:.0f} Wh "
                                 f"usable above the energy reserve")
    return estimate


def _reserve_fraction(mission: Mission) -> float:
    return float(mission.safety.energy_reserve) / 100.0


def _element(mission: Mission, site: _Site, element: RouteElement, here: _Where) -> ElementEstimate:
    p = element.params
    if isinstance(p, Transit):
        return _transit(mission, site, element.id, p, here)
    if isinstance(p, Survey):
        return _survey(mission, site, element.id, p, here)
    if isinstance(p, Explore):
        return _adaptive(mission, element, here, p.budget)
    if isinstance(p, Inspect):
        obj = mission.object(p.object)
        count = len(obj.targets) if p.targets == "all" else len(p.targets)
        return _adaptive(mission, element, here, 0.5 * p.search.budget + count * TARGET_WORK_S, obj.pose)
    assert isinstance(p, Reference)
    obj = mission.object(p.object)
    count = len(obj.characteristic_points) if p.point_sets == "all" else len(p.point_sets)
    return _adaptive(mission, element, here, count * 2.0 * len(p.offsets) + REFERENCE_FINE_S, obj.pose)


def _energy(mission: Mission, duration_s: float, moving_s: float, speed: float) -> float:
    v = mission.vehicle
    ratio = speed / v.cruise_speed
    return (v.hotel_power_w * duration_s + v.propulsion_power_w * ratio**3 * moving_s) / 3600.0


def vertical_time(dz: float, max_vertical_speed: float) -> float:
    """Seconds for the depth loop to bring a depth error `dz` within the tolerance band.

    >>> round(vertical_time(10.0, 0.5), 2)   # 8.75 m at 0.5 m/s, then the loop's exponential tail to 1 m
    18.06
    """
    err = abs(dz)
    if err <= DEPTH_TOLERANCE_M:
        return 0.0
    knee = max_vertical_speed / DEPTH_GAIN  # above this error the loop is at its rate limit
    linear = max(err - knee, 0.0) / max_vertical_speed
    return linear + math.log(min(err, knee) / DEPTH_TOLERANCE_M) / DEPTH_GAIN if min(err, knee) > DEPTH_TOLERANCE_M \
        else linear


def leg_time(distance: float, speed: float, acceleration: float, capture: float) -> float:
    """Seconds to fly a straight leg from rest and stop inside the capture circle, as the transit agent flies it:
    accelerate, cruise, then slow down in proportion to the distance left over the last three capture radii (no
    slower than `SLOW_SPEED_M_S`), until inside a quarter to a whole capture radius."""
    slow_zone = 3.0 * capture
    stop = 0.5 * capture
    if distance <= stop:
        return 0.0
    accel = speed / (2.0 * acceleration)  # the time lost accelerating from rest, against cruising all along
    if distance <= slow_zone:
        return accel + _slow_time(distance, stop, speed, slow_zone)
    return accel + (distance - slow_zone) / speed + _slow_time(slow_zone, stop, speed, slow_zone)


def _slow_time(start: float, stop: float, speed: float, zone: float) -> float:
    floor_at = SLOW_SPEED_M_S * zone / speed  # below this distance left, the floor speed holds
    t = 0.0
    if start > floor_at:
        t += zone / speed * math.log(start / max(floor_at, stop))
    if floor_at > stop:
        t += (min(start, floor_at) - stop) / SLOW_SPEED_M_S
    return t


def _transit(mission: Mission, site: _Site, ident: str, p: Transit, here: _Where) -> ElementEstimate:
    goal = (mission.home.north, mission.home.east) if isinstance(p.to, str) else (p.to.north, p.to.east)
    dn, de = goal[0] - here.north, goal[1] - here.east
    distance = math.hypot(dn, de)
    speed = p.speed or mission.vehicle.cruise_speed
    along = (site.current[0] * dn + site.current[1] * de) / distance if distance > 1e-9 else 0.0
    ground = max(speed + along, 0.2 * speed)
    moving = leg_time(distance, ground, mission.vehicle.max_acceleration, p.capture_radius)
    depth = here.depth
    if p.depth is not None:
        depth = p.depth
    elif p.altitude is not None:
        at = site.depth_at_altitude(goal[0], goal[1], p.altitude)
        depth = at if at is not None else here.depth
    duration = max(moving, vertical_time(depth - here.depth, mission.vehicle.max_vertical_speed))
    climb = abs(depth - here.depth)
    path = ((here.north, here.east), goal)
    here.north, here.east, here.depth = goal[0], goal[1], depth
    return ElementEstimate(ident, "transit", distance + climb, duration,
                           _energy(mission, duration, moving, speed), "plan", path=path)


def _survey(mission: Mission, site: _Site, ident: str, p: Survey, here: _Where) -> ElementEstimate:
    from planners.coverage import coverage_fraction, line_spacing, meander, swath_width

    mbes = mission.sensors.mbes
    if mbes is None:
        return ElementEstimate(ident, "survey", 0.0, 0.0, 0.0, "plan")
    speed = p.speed or mission.vehicle.cruise_speed
    if not site.plan_surveys:
        distance = survey_track_m(p, mbes.swath_deg, mission.vehicle.turn_radius)
        duration = distance / speed
        here.north = sum(v[0] for v in p.area) / len(p.area)  # where it ends is the plan's: take the middle
        here.east = sum(v[1] for v in p.area) / len(p.area)
        return ElementEstimate(ident, "survey", distance, duration, _energy(mission, duration, duration, speed), "area")
    plan = site.plans.get(ident)
    if plan is None:
        spacing = line_spacing(p.altitude, mbes.swath_deg, p.overlap)
        plan = site.plans[ident] = meander(p.area, p.exclude, spacing=spacing, heading=p.heading,
                                           turn_radius=mission.vehicle.turn_radius, start=(here.north, here.east))
    first = plan.waypoints[0]
    approach = math.hypot(first[0] - here.north, first[1] - here.east)
    distance = approach + plan.length_m
    duration = distance / speed + speed / (2.0 * mission.vehicle.max_acceleration)
    path = ((here.north, here.east), *((float(w[0]), float(w[1])) for w in plan.waypoints))
    last = plan.waypoints[-1]
    depth = site.depth_at_altitude(float(last[0]), float(last[1]), p.altitude)
    here.north, here.east = float(last[0]), float(last[1])
    if depth is not None:
        duration = max(duration, vertical_time(depth - here.depth, mission.vehicle.max_vertical_speed))
        here.depth = depth
    cover = 100.0 * coverage_fraction(plan, p.area, p.exclude, swath_width(p.altitude, mbes.swath_deg))
    return ElementEstimate(ident, "survey", distance, duration, _energy(mission, duration, duration, speed), "plan",
                           round(cover, 2), path)


def survey_track_m(p: Survey, swath_deg: float, turn_radius: float) -> float:
    """A survey's track sized from its area: the free area over the line spacing, plus a half-circle turn (at
    least the spacing) per line across the area's narrowest width."""
    from shapely.geometry import Polygon as ShapelyPolygon
    from shapely.ops import unary_union

    from planners.coverage import line_spacing

    spacing = line_spacing(p.altitude, swath_deg, p.overlap)
    area = ShapelyPolygon([(e, n) for n, e in p.area])
    free = area.difference(unary_union([ShapelyPolygon([(e, n) for n, e in z]) for z in p.exclude]))
    box = area.minimum_rotated_rectangle.exterior.coords
    sides = [math.dist(box[k], box[k + 1]) for k in range(2)]
    lines = math.ceil(min(sides) / spacing) + 1
    return float(free.area / spacing + (lines - 1) * max(math.pi * turn_radius, spacing))


def _adaptive(mission: Mission, element: RouteElement, here: _Where, budget_s: float,
              at: Pose | None = None) -> ElementEstimate:
    """An adaptive element: its work from its budget, and for a known object the way there first (at the work
    speed: the agent approaches at it)."""
    from mission.agents.hover import WORK_SPEED_M_S  # (the agents package is heavy: imported only here)

    work = float(budget_s)
    approach = 0.0
    path: tuple[tuple[float, float], ...] = ()
    if at is not None:
        approach = math.hypot(at.north - here.north, at.east - here.east)
        path = ((here.north, here.east), (at.north, at.east))
        here.north, here.east = at.north, at.east
    approach_s = approach / WORK_SPEED_M_S
    duration = approach_s + work
    if element.timeout is not None:
        duration = min(duration, element.timeout)
    moving = WORK_FRACTION_MOVING * work
    speed = STATION_KEEPING_SPEED_M_S
    energy = _energy(mission, duration, moving, speed) + _energy(mission, 0.0, approach_s, WORK_SPEED_M_S)
    return ElementEstimate(element.id, element.kind, approach + moving * speed, duration, energy, "budget",
                           path=path)


def coverage_of(estimate: MissionEstimate) -> dict[str, float]:
    """The planned coverage of each survey element, by id."""
    return {e.id: e.coverage_percent for e in estimate.elements if e.coverage_percent is not None}


__all__ = ["Chart", "ElementEstimate", "MissionEstimate", "RouteEstimator", "estimate_mission", "leg_time",
           "vertical_time"]
