"""The order of an inspection's stops (seed 002 §3.4): a set before the targets referenced to it, and a re-plan
through another set when one is not recognised."""

from __future__ import annotations

import numpy as np

from mission.agents.inspect.itinerary import Itinerary
from mission.language.models import Target

SETS = {"module-top": np.array([[2, 1, -2], [6, 1, -2], [6, 4, -2], [2, 4, -2]], dtype=float),
        "skid-east": np.array([[8, 0, 0], [8, 5, 0], [7, 0.5, -0.3], [7, 4.5, -0.3]], dtype=float)}
TARGETS = {"valve": Target(id="valve", at=(7.2, 1.0, -0.2), reference="skid-east", photos=2),
           "hatch": Target(id="hatch", at=(4.0, 2.5, -2.0), reference="module-top")}


def test_every_set_comes_before_the_targets_referenced_to_it():
    itinerary = Itinerary(SETS, TARGETS, "auto", np.array([-5.0, 2.5, -8.0]), seed=1, set_cost_m=8.0)
    queue = itinerary.queue
    assert sorted(queue) == sorted([("set", "module-top"), ("set", "skid-east"), ("target", "valve"),
                                    ("target", "hatch")])
    for tid, target in TARGETS.items():
        assert queue.index(("set", target.reference)) < queue.index(("target", tid))


def test_as_listed_keeps_the_missions_order():
    itinerary = Itinerary(SETS, TARGETS, "as-listed", np.zeros(3), seed=1, set_cost_m=8.0)
    assert itinerary.queue == [("set", "skid-east"), ("target", "valve"), ("set", "module-top"), ("target", "hatch")]


def test_a_set_that_fails_hands_its_targets_to_another_set():
    itinerary = Itinerary(SETS, TARGETS, "as-listed", np.zeros(3), seed=1, set_cost_m=8.0)
    itinerary.queue.pop(0)  # skid-east was tried, and failed
    record = itinerary.replan("skid-east", np.array([7.5, 2.5, -4.0]), pending={"valve", "hatch"})
    assert record["binding"] == {"valve": "module-top", "hatch": "module-top"}
    assert "skid-east" in itinerary.failed and ("set", "skid-east") not in itinerary.queue
    assert itinerary.queue.index(("set", "module-top")) < itinerary.queue.index(("target", "valve"))
    assert itinerary.nearest_usable_set(np.array([8.0, 2.5, 0.0])) == "module-top"


def test_re_referencing_prefers_a_detectable_set_unless_it_is_much_farther():
    plain = Itinerary(SETS, TARGETS, "auto", np.zeros(3), seed=1, set_cost_m=8.0)
    rated = Itinerary(SETS, TARGETS, "auto", np.zeros(3), seed=1, set_cost_m=8.0,
                      ratings={"module-top": 0.5, "skid-east": 0.1})
    near_skid = np.array([6.5, 2.5, -0.5])  # 2.9 m from module-top's centre, 1.1 m from skid-east's
    assert plain.nearest_usable_set(near_skid) == "skid-east"
    assert rated.nearest_usable_set(near_skid) == "module-top"
    beside_skid = np.array([7.5, 2.5, -0.2])  # 0.05 m from skid-east: a fifth of the rating still wins
    assert rated.nearest_usable_set(beside_skid) == "skid-east"
