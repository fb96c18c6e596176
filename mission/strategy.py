"""The strategic level's ordering (seed 002 §3.4): when a route inspects several known objects one after another,
visit them in the order that makes the shortest path from where the vehicle is (an open travelling-salesman
path over the objects' database positions); each object's own sets and targets are ordered by its agent.

The graph of objects is the complete graph of their positions, solved by `planners.ordering.solve_tsp` (exact up
to 12 objects). Measured against networkx's Christofides (`benchmarks/networkx_timing.py`, the cycle from the
vehicle less its return leg) on 4, 8, 12 and 20 objects: its paths were 10–18 % longer; its time was 0.06–5.1×
ours over two runs on a loaded machine (all under 20 ms either way). Shorter paths decide: ours stays.
"""

from __future__ import annotations

from collections.abc import Sequence

from mission.language.models import Mission, RouteElement


def inspection_run(route: Sequence[RouteElement], start: int) -> int:
    """The end (exclusive) of the run of consecutive `inspect` elements with `order: auto` beginning at `start`."""
    end = start
    while end < len(route) and route[end].inspect is not None and route[end].inspect.order == "auto":  # type: ignore[union-attr]
        end += 1
    return end


def order_objects(mission: Mission, elements: Sequence[RouteElement], north: float, east: float,
                  seed: int = 0) -> list[RouteElement]:
    """These inspect elements in the shortest visiting order from (north, east).

    Exact for up to 12 objects (Held–Karp), iterated local search beyond (`planners.ordering.solve_tsp`)."""
    from planners.ordering import solve_tsp

    if len(elements) < 2:
        return list(elements)
    points = [(north, east)]
    for e in elements:
        assert e.inspect is not None
        pose = mission.object(e.inspect.object).pose
        points.append((pose.north, pose.east))
    tour = solve_tsp(points, start=0, closed=False, seed=seed)
    return [elements[i - 1] for i in tour.order[1:]]
