"""The strategic level (seed 002 §1, §3.4): which of the route's work to do, and in which order, under the
mission's time and energy budgets. The executive asks it before the first element and again after every element
(`plan_route` on what is left), so that the plan follows what really happened: an element that failed or ended
early frees time for work dropped before, one that overran makes room by dropping more.

Order. The route's transits and surveys are its skeleton and keep their places, as does work on an object the
database does not chart (`explore: {object: detected}`) and an inspection with `order: as-listed`. Between two of
these, the work bound to known objects (`inspect`, `reference`, `explore` of a database object) is grouped into
visits, one per run of consecutive elements on the same object (their own order kept), and the visits are flown in
the shortest order from where the vehicle will be: an open travelling-salesman path over the objects' database
positions, exact up to 12 objects (`planners.ordering.solve_tsp`). `strategy: {order: as-listed}` keeps the route
as written.

Budget. The remaining route is estimated (`mission.estimate.RouteEstimator`) against the time left before
`max_duration` and the energy left above the reserve, less `strategy.budget_margin`. While it does not fit, the
work of lowest `priority` is dropped (the later of equals first; an explore of `detected` objects goes with the
survey it depends on). Transits are never dropped: they carry the vehicle, and the last one brings it home. If
dropping every piece of work would still not make the route fit, nothing is dropped: the safety monitors end the
mission at its limits, as they would anyway.

Measured against networkx's Christofides (`benchmarks/networkx_timing.py`, the cycle from the vehicle less its
return leg) on 4, 8, 12 and 20 objects, the exact ordering's paths were 10–18 % shorter, in under 20 ms.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from mission.estimate import ElementEstimate, RouteEstimator
from mission.language.models import Mission, RouteElement
from mission.vehicle import NavState


@dataclass(frozen=True)
class Budget:
    """What is left when the plan is made: the vehicle's position, the mission time and the energy."""

    north: float
    east: float
    depth: float
    time_s: float = 0.0
    energy_wh: float | None = None  # None: the vehicle's full battery


@dataclass
class RoutePlan:
    """The elements to fly, in order, with their estimates, and the work dropped with the reason."""

    order: list[RouteElement]
    estimates: list[ElementEstimate]
    dropped: list[tuple[RouteElement, str]] = field(default_factory=list)
    fits: bool = True

    @property
    def duration_s(self) -> float:
        return sum(e.duration_s for e in self.estimates)

    @property
    def energy_wh(self) -> float:
        return sum(e.energy_wh for e in self.estimates)


def bound_object(mission: Mission, element: RouteElement) -> str | None:
    """The database object an element works on, if the strategic level may move it."""
    if mission.strategy.order == "as-listed":
        return None
    if element.inspect is not None:
        return element.inspect.object if element.inspect.order == "auto" else None
    if element.reference is not None:
        return element.reference.object
    if element.explore is not None and any(o.id == element.explore.object for o in mission.objects):
        return element.explore.object
    return None


def order_route(mission: Mission, elements: Sequence[RouteElement], estimator: RouteEstimator,
                start: Budget) -> list[RouteElement]:
    """`elements` with each stretch of object-bound work between fixed elements in its shortest visiting order."""
    from planners.ordering import solve_tsp

    out: list[RouteElement] = []
    where = (start.north, start.east, start.depth)
    i = 0
    while i < len(elements):
        if bound_object(mission, elements[i]) is None:
            where = estimator.end_of(elements[i], *where)
            out.append(elements[i])
            i += 1
            continue
        visits: list[list[RouteElement]] = []
        while i < len(elements) and (obj := bound_object(mission, elements[i])) is not None:
            if visits and bound_object(mission, visits[-1][-1]) == obj:
                visits[-1].append(elements[i])
            else:
                visits.append([elements[i]])
            i += 1
        if len(visits) > 1:
            points = [where[:2]]
            for visit in visits:
                pose = mission.object(bound_object(mission, visit[0]) or "").pose
                points.append((pose.north, pose.east))
            tour = solve_tsp(points, start=0, closed=False, seed=mission.seed)
            visits = [visits[k - 1] for k in tour.order[1:]]
        for visit in visits:
            for element in visit:
                where = estimator.end_of(element, *where)
                out.append(element)
    return out


def plan_route(mission: Mission, remaining: Sequence[RouteElement], start: Budget,
               estimator: RouteEstimator | None = None) -> RoutePlan:
    """The strategic plan for `remaining` (in the route's order) from `start` (see the module docstring)."""
    estimator = estimator or RouteEstimator(mission)
    margin = 1.0 - mission.strategy.budget_margin / 100.0
    time_left = (mission.safety.max_duration - start.time_s) * margin
    energy = mission.vehicle.energy_wh if start.energy_wh is None else start.energy_wh
    energy_left = (energy - mission.vehicle.energy_wh * mission.safety.energy_reserve / 100.0) * margin

    def planned(elements: Sequence[RouteElement]) -> RoutePlan:
        order = order_route(mission, elements, estimator, start)
        return RoutePlan(order, estimator.route(order, start.north, start.east, start.depth))

    def fits(plan: RoutePlan) -> bool:
        return plan.duration_s <= time_left and plan.energy_wh <= energy_left

    plan = planned(remaining)
    if fits(plan):
        return plan
    kept = list(remaining)
    dropped: list[tuple[RouteElement, str]] = []
    while not fits(candidate := planned(kept)):
        work = [e for e in kept if e.kind != "transit"]
        if not work:
            plan.fits = False  # not even the transits fit: keep everything, the monitors end it at its limits
            return plan
        victim = min(work, key=lambda e: (e.priority, -kept.index(e)))
        why = (f"priority {victim.priority}: the route needed {candidate.duration_s / 60:.0f} min and "
               f"{candidate.energy_wh:.0f} Wh, {max(time_left, 0.0) / 60:.0f} min and {max(energy_left, 0.0):.0f} Wh "
               f"were left (less the {mission.strategy.budget_margin:g} % margin)")
        for element in [victim, *_dependents(kept, victim)]:
            kept.remove(element)
            dropped.append((element, why if element is victim else f"depends on '{victim.id}', dropped"))
    candidate.dropped = dropped
    return candidate


def _dependents(elements: Sequence[RouteElement], victim: RouteElement) -> list[RouteElement]:
    """Explorations of `detected` objects that only `victim` (a survey) would detect."""
    if victim.survey is None:
        return []
    out = []
    last_survey: RouteElement | None = None
    for element in elements:
        if element.survey is not None:
            last_survey = element
        elif element.explore is not None and element.explore.object == "detected" and last_survey is victim:
            out.append(element)
    return out


class StrategicLevel:
    """The executive's strategic level: `next(nav)` re-plans what is left of the route and gives the element to
    fly now (None when nothing is left to fly); a plan that changes from what was expected is a `route_planned`
    event. `dropped` is the work the last plan left out."""

    def __init__(self, mission: Mission, emit: Callable[..., Any], start_time: float):
        self.mission, self.emit, self.start_time = mission, emit, start_time
        self.remaining = list(mission.route)
        self.estimator = RouteEstimator(mission)
        self.expected: tuple[list[str], list[str]] = ([e.id for e in self.remaining], [])
        self.dropped: list[tuple[RouteElement, str]] = []

    def next(self, nav: NavState) -> RouteElement | None:
        if not self.remaining:
            return None
        plan = plan_route(self.mission, self.remaining, Budget(nav.north, nav.east, nav.depth,
                                                              nav.time - self.start_time, nav.energy_wh),
                          self.estimator)
        shape = ([e.id for e in plan.order], [e.id for e, _ in plan.dropped])
        if shape != self.expected:
            self.emit("route_planned", nav.time, elements=shape[0],
                      dropped=[{"element": e.id, "reason": why} for e, why in plan.dropped],
                      estimated_duration_s=round(plan.duration_s, 1), estimated_energy_wh=round(plan.energy_wh, 1))
        self.dropped = plan.dropped
        if not plan.order:
            return None
        self.expected = (shape[0][1:], shape[1])
        self.remaining.remove(plan.order[0])
        return plan.order[0]

    def skip_rest(self) -> list[RouteElement]:
        """What is left, now that the mission is aborting (in the route's order); nothing is left to plan."""
        rest, self.remaining = self.remaining, []
        return rest


__all__ = ["Budget", "StrategicLevel", "RoutePlan", "bound_object", "order_route", "plan_route"]
