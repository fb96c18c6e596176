"""The strategic level (`mission.strategy`): object-bound work in the shortest visiting order between the
route's fixed elements, and the lowest-priority work dropped when the time or energy budget falls short, before
the dive and again after each element."""

import itertools
import math

import pytest
import yaml
from conftest import MISSIONS

from mission.estimate import RouteEstimator
from mission.executive import ElementStatus, Executive
from mission.language.models import Mission
from mission.strategy import Budget, bound_object, order_route, plan_route
from mission.testing import FakeAgent, StubVehicle

POSES = {"a": (100.0, 0.0), "b": (10.0, 5.0), "c": (55.0, -40.0), "d": (60.0, 30.0), "e": (20.0, 60.0)}


def five_objects(**changes) -> Mission:
    """Five charted objects, a dive, an inspection of each (listed in a poor order), and the way home."""
    data = yaml.safe_load((MISSIONS.parent / "docs" / "missions" / "manifold_inspection.yaml").read_text())
    data.pop("world", None)
    template = data["objects"][0]
    data["objects"] = [{**template, "id": f"obj-{k}", "pose": {**template["pose"], "north": n, "east": e}}
                       for k, (n, e) in POSES.items()]
    data["route"] = [{"id": "dive", "transit": {"to": {"north": 0, "east": 0}, "depth": 40}}] + [
        {"id": f"inspect-{k}", "inspect": {"object": f"obj-{k}"}} for k in POSES] + [
        {"id": "home", "transit": {"to": "home", "depth": 0}}]
    for key, value in changes.items():
        data[key] = {**data.get(key, {}), **value} if isinstance(value, dict) else value
    return Mission.model_validate(data)


def path_length(keys) -> float:
    points = [(0.0, 0.0)] + [POSES[k] for k in keys]
    return sum(math.dist(p, q) for p, q in itertools.pairwise(points))


def inspected(order) -> tuple[str, ...]:
    return tuple(e.inspect.object.removeprefix("obj-") for e in order if e.inspect is not None)


def test_five_objects_are_visited_in_the_shortest_order_between_the_fixed_transits():
    mission = five_objects()
    plan = plan_route(mission, mission.route, Budget(0.0, 0.0, 0.0))
    assert plan.order[0].id == "dive" and plan.order[-1].id == "home" and plan.dropped == []
    best = min(itertools.permutations(POSES), key=path_length)
    assert sorted(inspected(plan.order)) == sorted(POSES)
    assert path_length(inspected(plan.order)) == pytest.approx(path_length(best), rel=1e-9)
    assert path_length(inspected(plan.order)) < 0.8 * path_length(tuple(POSES))  # the listed order is much worse


def test_as_listed_keeps_the_route_and_work_on_one_object_stays_together_in_its_order():
    listed = five_objects(strategy={"order": "as-listed"})
    assert inspected(plan_route(listed, listed.route, Budget(0, 0, 0)).order) == tuple(POSES)
    data = five_objects().model_dump(exclude_none=True)
    data["route"].insert(1, {"id": "reference-a", "reference": {"object": "obj-a"}})  # then inspect-a
    mission = Mission.model_validate(data)
    order = [e.id for e in order_route(mission, mission.route, RouteEstimator(mission), Budget(0, 0, 0))]
    assert order.index("inspect-a") == order.index("reference-a") + 1
    assert bound_object(mission, mission.route[0]) is None  # a transit is part of the skeleton


def test_when_the_budget_falls_short_the_lowest_priority_work_is_dropped_and_never_a_transit():
    mission = five_objects()
    need = plan_route(mission, mission.route, Budget(0, 0, 0)).duration_s
    data = five_objects().model_dump(exclude_none=True)
    for element, priority in zip(data["route"][1:6], (3, 1, 5, 2, 4), strict=True):
        element["priority"] = priority
    data["safety"]["max_duration"] = 0.75 * need / 0.9  # after the 10 % margin, three quarters of the route
    mission = Mission.model_validate(data)
    plan = plan_route(mission, mission.route, Budget(0, 0, 0))
    dropped = [e.id for e, _ in plan.dropped]
    assert dropped[:2] == ["inspect-b", "inspect-d"]  # priorities 1 and 2, in that order
    assert all(e.kind != "transit" for e, _ in plan.dropped)
    assert plan.duration_s <= 0.75 * need + 1e-6 and "priority 1" in plan.dropped[0][1]
    assert {"dive", "home"} <= {e.id for e in plan.order}


def test_nothing_is_dropped_when_even_the_transits_alone_do_not_fit():
    mission = five_objects(safety={"max_duration": 60.0})
    plan = plan_route(mission, mission.route, Budget(0, 0, 0))
    assert plan.dropped == [] and not plan.fits and len(plan.order) == len(mission.route)


def test_the_executive_drops_work_before_the_dive_and_takes_it_back_when_elements_end_early():
    """Inspections are estimated from their budgets; these fake ones end after 20 s, so after the first the plan
    has the time for the dropped work again."""
    m = five_objects()
    full = plan_route(m, m.route, Budget(0, 0, 0))
    data = m.model_dump(exclude_none=True)
    data["safety"]["max_duration"] = 0.6 * full.duration_s / 0.9
    data["route"][2]["priority"] = -1  # inspect-b: the first to go
    mission = Mission.model_validate(data)
    events: list[tuple[str, float, dict]] = []
    vehicle = StubVehicle.for_mission(mission, control_period=1.0)
    agents = {"inspect": lambda: FakeAgent(outcome="succeed", script=[]), "transit": None}
    from mission.agents.transit import TransitAgent

    agents["transit"] = TransitAgent
    report = Executive(mission, vehicle, lambda e, t, **f: events.append((e, t, f)), agents=agents).run()
    plans = [f for e, _, f in events if e == "route_planned"]
    assert plans and [d["element"] for d in plans[0]["dropped"]][0] == "inspect-b"  # said before the dive
    assert report.completed
    statuses = {r.id: r.status for r in report.elements}
    assert statuses["inspect-b"] is ElementStatus.SUCCEEDED  # taken back once the others ended early
    assert any(p["dropped"] == [] for p in plans[1:])
