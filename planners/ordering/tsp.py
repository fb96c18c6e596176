"""Visiting orders (seed 002 §3.4: the order of point sets and targets that minimises the distance travelled):
`solve_tsp` for a plain tour or path and `solve_precedence` for a path from the vehicle with precedences.

Up to `EXACT_MAX_STOPS` stops besides the start the answer is exact (dynamic programming); beyond, an iterated
local search runs a budget of kicks that grows with the number of stops, so the result depends only on the inputs
and the seed. `time_limit_s` adds a wall-clock cap; when it cuts the search short the result also depends on the
machine.
"""

from __future__ import annotations

import random
import time
from collections.abc import Sequence
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from .construct import nearest_feasible_path, repair_precedence, savings_tour
from .costs import Array, Tour, as_cost_matrix, distance_matrix, is_symmetric, neighbour_lists, tour_cost
from .exact import EXACT_MAX_STOPS, held_karp
from .kicks import iterated_precedence_search
from .local import ClosedTour, iterated_local_search
from .precedence import PrecedencePath, precedence_cycle, violations

Method = Literal["auto", "exact", "heuristic"]
NEIGHBOURS = 10                   # candidate list length
KICKS_PER_STOP = 0.7              # tours: kicks = effort · 0.7 · n (n = 200: ~80 ms on one unloaded core)
BREADTH = (6, 5)                  # candidates tried for the first and second edge added by a 3-opt move
DEPTH = 6                         # longest chain of 3-opt moves (Lin–Kernighan style) tried from one stop
MAX_SEGMENT = 50                  # longest segment a double-bridge kick moves (tours)
PRECEDENCE_KICKS_PER_STOP = 5.0   # paths with precedence: kicks = effort · max(5 · n, 600)
PRECEDENCE_MIN_KICKS = 600
PRECEDENCE_MAX_SEGMENT = 12       # longest segment a double-bridge kick moves (paths)
PRECEDENCE_SLACK = 0.01           # record-to-record travel: kicks kept within 1 % of the best path
PRECEDENCE_RUNS = 3               # independent searches first, cycling over the starting paths
PRECEDENCE_RUN_SHARE = 0.5        # share of the budget they spend; the best goes on with the rest
PRECEDENCE_TSP_EFFORT = 0.5       # effort of the precedence-free path the search may start from


def _costs(points: ArrayLike | None, cost: ArrayLike | None) -> Array:
    if (points is None) == (cost is None):
        raise ValueError("give either points or a cost matrix")
    if points is not None:
        return distance_matrix(points)
    assert cost is not None
    return as_cost_matrix(cost)


def _use_exact(method: Method, stops: int) -> bool:
    if method not in ("auto", "exact", "heuristic"):
        raise ValueError(f"unknown method {method!r} (auto, exact or heuristic)")
    return method == "exact" or (method == "auto" and stops <= EXACT_MAX_STOPS)


def solve_tsp(points: ArrayLike | None = None, *, cost: ArrayLike | None = None, start: int = 0,
              closed: bool = True, seed: int = 0, time_limit_s: float | None = None, method: Method = "auto",
              effort: float = 1.0) -> Tour:
    """The shortest tour through `points` (n × 2 or n × 3) or by a `cost` matrix, from `start`; closed returns
    to the start, open ends anywhere. Exact up to 12 stops besides the start; beyond, iterated Lin–Kernighan-style
    local search from the savings tour (symmetric costs), `effort` scaling its budget of 0.7 · n kicks. A closed
    tour is given the way round whose second stop has the smaller index.

    >>> square = [[0, 0], [10, 10], [0, 10], [10, 0]]
    >>> solve_tsp(square).order, solve_tsp(square).cost
    ((0, 2, 1, 3), 40.0)
    >>> solve_tsp(square, closed=False, start=1).cost
    30.0
    """
    c = _costs(points, cost)
    n = len(c)
    if not 0 <= start < n:
        raise ValueError(f"start {start} is not one of the {n} stops")
    if n <= 3 or _use_exact(method, n - 1):
        exact = held_karp(c, start, closed)
        return Tour(_oriented(exact.order, closed), exact.cost, closed, exact=True)
    if not is_symmetric(c):
        raise ValueError("the heuristic needs symmetric costs (asymmetric ones are solved exactly up to 12 stops)")
    deadline = None if time_limit_s is None else time.perf_counter() + time_limit_s
    rng = random.Random(seed)
    kicks = max(20, int(round(effort * KICKS_PER_STOP * n)))
    near = neighbour_lists(c, NEIGHBOURS)
    order = savings_tour(c, near)
    if closed:
        tour = ClosedTour(c.tolist(), near, order, BREADTH, DEPTH)
        iterated_local_search(tour, rng, kicks, MAX_SEGMENT, deadline)
        seq = _rotate(tour.order, start)
        return Tour(_oriented(seq, True), tour_cost(seq, c, True), True)
    # an open path is a closed tour through a dummy stop tied to the start by an edge too cheap to give up
    # (−big) and free (0) to every other stop: the tour's other dummy edge marks where the path ends
    dummy = n
    big = 4.0 * float(c.max()) + 1.0
    aug = np.zeros((n + 1, n + 1))
    aug[:n, :n] = c
    aug[dummy, start] = aug[start, dummy] = -big
    seq = _rotate(order, start)
    if c[start, seq[1]] > c[start, seq[-1]]:
        seq = [start, *seq[:0:-1]]
    tour = ClosedTour(aug.tolist(), [*near, []], [*seq, dummy], BREADTH, DEPTH)
    iterated_local_search(tour, rng, kicks, MAX_SEGMENT, deadline, fixed=(dummy, start))
    cyc = _rotate(tour.order, start)
    path = cyc[1:] if cyc[1] != dummy else cyc[:0:-1]
    path = [start, *[v for v in path if v not in (dummy, start)]]
    return Tour(tuple(path), tour_cost(path, c, False), False)


def _oriented(order: Sequence[int], closed: bool) -> tuple[int, ...]:
    seq = tuple(int(v) for v in order)
    if closed and len(seq) > 2 and seq[1] > seq[-1]:
        seq = (seq[0], *seq[:0:-1])
    return seq


def _rotate(order: Sequence[int], start: int) -> list[int]:
    seq = list(order)
    i = seq.index(start)
    return seq[i:] + seq[:i]


def _precedence_lists(n: int, start: int, precedences: Sequence[tuple[int, int]]) -> tuple[list[list[int]],
                                                                                           list[list[int]]]:
    need: list[list[int]] = [[] for _ in range(n)]
    follow: list[list[int]] = [[] for _ in range(n)]
    for before, after in precedences:
        if not (0 <= before < n and 0 <= after < n):
            raise ValueError(f"precedence ({before}, {after}) names a stop outside 0…{n - 1}")
        if before == after:
            raise ValueError(f"precedence ({before}, {after}) ties a stop to itself")
        if after == start:
            raise ValueError(f"stop {before} must precede the start {start}: infeasible")
        if before == start:
            continue
        need[after].append(before)
        follow[before].append(after)
    cycle = precedence_cycle(n, need)
    if cycle is not None:
        raise ValueError("the precedence constraints admit no order (they contain a cycle: "
                         f"{' → '.join(map(str, [*cycle, cycle[0]]))})")
    return need, follow


def solve_precedence(cost: ArrayLike, start: int = 0, precedences: Sequence[tuple[int, int]] = (), seed: int = 0,
                     time_limit_s: float | None = None, method: Method = "auto", effort: float = 1.0) -> Tour:
    """The cheapest path from `start` through every stop of the `cost` matrix with each `(before, after)` pair of
    `precedences` in that order. Exact up to 12 stops besides the start. Beyond, iterated local search from three
    feasible starting paths (nearest feasible neighbour; the shortest path ignoring precedence, repaired by
    pulling predecessors forward or by deferring the stops that come too early), the best of them then searched
    further; moves and kicks keep every precedence (see `precedence` and `kicks`); 2-opt and reversed insertions
    only when costs are symmetric. Never returns an order that breaks a pair.

    >>> c = distance_matrix([[0, 0], [1, 0], [2, 0], [3, 0]])
    >>> solve_precedence(c, 0, [(3, 2)]).order
    (0, 1, 3, 2)
    """
    c = as_cost_matrix(cost)
    n = len(c)
    if not 0 <= start < n:
        raise ValueError(f"start {start} is not one of the {n} stops")
    need, follow = _precedence_lists(n, start, precedences)
    if n <= 2 or _use_exact(method, n - 1):
        return held_karp(c, start, closed=False, precedences=precedences)
    deadline = None if time_limit_s is None else time.perf_counter() + time_limit_s
    rng = random.Random(seed)
    kicks = max(20, int(round(effort * max(PRECEDENCE_KICKS_PER_STOP * n, PRECEDENCE_MIN_KICKS))))
    end = n                                           # a sentinel after the last stop, free to reach
    aug = np.zeros((n + 1, n + 1))
    aug[:n, :n] = c
    symmetric = is_symmetric(c)
    starts = [nearest_feasible_path(c, start, need)]
    if symmetric:                                     # the shortest path ignoring precedence, then repaired
        left = None if deadline is None else max(0.0, deadline - time.perf_counter())
        free = solve_tsp(cost=c, start=start, closed=False, seed=seed, effort=PRECEDENCE_TSP_EFFORT,
                         time_limit_s=left)
        starts += [repair_precedence(free.order, need, pull) for pull in (True, False)]
    starts.sort(key=lambda o: tour_cost(o, c, False))
    rows, near = aug.tolist(), [*neighbour_lists(c, NEIGHBOURS), []]
    # independent searches from the starting paths (the search can settle in a poor arrangement of whole
    # groups of stops that kicks do not undo), the rest of the budget then spent on the best of them
    runs = [starts[i % len(starts)] for i in range(PRECEDENCE_RUNS)]
    share = int(kicks * PRECEDENCE_RUN_SHARE) // len(runs)
    best: PrecedencePath | None = None
    for order in runs:
        path = PrecedencePath(rows, near, [*order, end], [*need, []], [*follow, []], symmetric=symmetric)
        iterated_precedence_search(path, rng, share, PRECEDENCE_MAX_SEGMENT, deadline, PRECEDENCE_SLACK)
        if best is None or path.length() < best.length() - 1e-9:
            best = path
    assert best is not None
    path = best
    iterated_precedence_search(path, rng, kicks - share * len(runs), PRECEDENCE_MAX_SEGMENT, deadline,
                               PRECEDENCE_SLACK)
    seq = path.order[:-1]
    if sorted(seq) != list(range(n)) or seq[0] != start or violations(seq, precedences):
        raise RuntimeError("internal error: the precedence search returned an infeasible order")
    return Tour(tuple(seq), tour_cost(seq, c, False), False)
