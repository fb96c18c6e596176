"""The strategic level orders consecutive inspections of several objects by the shortest path from the vehicle."""

import itertools
import math

import yaml
from conftest import MISSIONS

from mission.language.models import Mission
from mission.strategy import inspection_run, order_objects

POSES = {"a": (100.0, 0.0), "b": (10.0, 5.0), "c": (55.0, -40.0), "d": (60.0, 30.0), "e": (20.0, 60.0)}


def several_objects() -> Mission:
    data = yaml.safe_load((MISSIONS.parent / "docs" / "missions" / "manifold_inspection.yaml").read_text())
    template = data["objects"][0]
    data["objects"] = [{**template, "id": f"obj-{k}", "pose": {**template["pose"], "north": n, "east": e}}
                       for k, (n, e) in POSES.items()]
    data["route"] = [{"id": "go", "transit": {"to": {"north": 0, "east": 0}, "depth": 40}}] + [
        {"id": f"inspect-{k}", "inspect": {"object": f"obj-{k}"}} for k in POSES] + [
        {"id": "listed", "inspect": {"object": "obj-a", "order": "as-listed"}}]
    return Mission.model_validate(data)


def path_length(keys: tuple[str, ...]) -> float:
    points = [(0.0, 0.0)] + [POSES[k] for k in keys]
    return sum(math.dist(p, q) for p, q in itertools.pairwise(points))


def test_consecutive_auto_inspections_form_one_run():
    mission = several_objects()
    assert inspection_run(mission.route, 1) == 1 + len(POSES)  # the as-listed one ends the run
    assert inspection_run(mission.route, 0) == 0


def test_objects_are_visited_in_the_shortest_order():
    mission = several_objects()
    ordered = order_objects(mission, mission.route[1:1 + len(POSES)], 0.0, 0.0)
    keys = tuple(e.inspect.object.removeprefix("obj-") for e in ordered)
    best = min(itertools.permutations(POSES), key=path_length)
    assert sorted(keys) == sorted(POSES)
    assert math.isclose(path_length(keys), path_length(best), rel_tol=1e-9)
    assert path_length(keys) < path_length(tuple(POSES))  # the listed order is worse: ordering matters here
