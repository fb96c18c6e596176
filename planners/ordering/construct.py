"""Starting orders for the local search of the visiting order (seed 002 §3.4): the greedy-edge tour (shortest edges
first, no stop of degree three, no early cycle), the savings tour (Clarke and Wright: the same greedy matching, but
of the edges that save most over going out and back from a central hub), and the nearest feasible neighbour for
paths with precedence.

The savings tour starts the plain-tour search: the savings tour is the shorter of the two on random fields, and
its overall shape, which the kicks of the local search rarely change wholesale, decides much of the last few tenths
of a percent (in `auv bench ordering` the search ends closer to LKH from it than from the greedy-edge tour).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .costs import Array


def savings_tour(cost: Array, neighbours: Sequence[Sequence[int]]) -> list[int]:
    """A closed tour by the savings heuristic (Clarke and Wright) for symmetric costs: with the hub h the stop of
    least total cost to all others, the candidate edges (each stop to its neighbours) are matched greedily in order
    of the saving cost[h, a] + cost[h, b] − cost[a, b], as `greedy_tour` matches them by length.

    >>> pts = np.array([[0, 0], [0, 1], [1, 1], [1, 0], [0.5, 0.5]], dtype=float)
    >>> c = np.sqrt(((pts[:, None] - pts[None]) ** 2).sum(-1))
    >>> sorted(savings_tour(c, [[4, 1, 3], [4, 0, 2], [4, 1, 3], [4, 0, 2], [0, 1, 2]]))
    [0, 1, 2, 3, 4]
    """
    hub = int(np.argmin(cost.sum(axis=1)))
    return greedy_tour(cost - cost[hub][:, None] - cost[hub][None, :], neighbours)


def greedy_tour(cost: Array, neighbours: Sequence[Sequence[int]]) -> list[int]:
    """A closed tour by the greedy-edge heuristic: candidate edges (each stop to its neighbours) are taken
    cheapest first while they keep every degree ≤ 2 and close no cycle; the fragments left are then joined end to
    cheapest free end. Symmetric costs (any sign: `savings_tour` passes negated savings).

    >>> pts = np.array([[0, 0], [0, 1], [1, 1], [1, 0]], dtype=float)
    >>> c = np.sqrt(((pts[:, None] - pts[None]) ** 2).sum(-1))
    >>> sorted(greedy_tour(c, [[1, 3], [0, 2], [1, 3], [0, 2]]))
    [0, 1, 2, 3]
    """
    n = len(cost)
    if n <= 3:
        return list(range(n))
    rows = np.repeat(np.arange(n), [len(nb) for nb in neighbours])
    cols = np.concatenate([np.asarray(nb, dtype=np.int64) for nb in neighbours])
    lo, hi = np.minimum(rows, cols), np.maximum(rows, cols)
    key = np.unique(lo * n + hi)
    lo, hi = key // n, key % n
    by_length = np.argsort(cost[lo, hi], kind="stable")
    degree = [0] * n
    root = list(range(n))
    adjacent: list[list[int]] = [[] for _ in range(n)]

    def find(x: int) -> int:
        while root[x] != x:
            root[x] = root[root[x]]
            x = root[x]
        return x

    edges = 0
    for a, b in zip(lo[by_length].tolist(), hi[by_length].tolist(), strict=True):
        if degree[a] < 2 and degree[b] < 2:
            ra, rb = find(a), find(b)
            if ra != rb:
                root[ra] = rb
                degree[a] += 1
                degree[b] += 1
                adjacent[a].append(b)
                adjacent[b].append(a)
                edges += 1
                if edges == n - 1:
                    break
    while edges < n - 1:                        # join fragments: a free end to the nearest free end elsewhere
        ends = [v for v in range(n) if degree[v] < 2]
        a = ends[0]
        ra = find(a)
        others = [v for v in ends if find(v) != ra]
        b = others[int(np.argmin(cost[a, others]))]
        root[ra] = find(b)
        degree[a] += 1
        degree[b] += 1
        adjacent[a].append(b)
        adjacent[b].append(a)
        edges += 1
    first = next(v for v in range(n) if degree[v] < 2)
    order = [first]
    previous, current = -1, first
    while len(order) < n:
        nxt = adjacent[current][0] if adjacent[current][0] != previous else adjacent[current][1]
        order.append(nxt)
        previous, current = current, nxt
    return order


def nearest_feasible_path(cost: Array, start: int, need: Sequence[Sequence[int]]) -> list[int]:
    """A path from `start` through every stop, each step to the nearest stop whose required predecessors
    (`need[v]`) are all visited.

    >>> c = np.array([[0, 1, 2], [1, 0, 1], [2, 1, 0]], dtype=float)
    >>> nearest_feasible_path(c, 0, [[], [2], []])
    [0, 2, 1]
    """
    n = len(cost)
    waiting = np.array([len(set(need[v]) - {start}) for v in range(n)], dtype=np.int64)
    followers: list[list[int]] = [[] for _ in range(n)]
    for v in range(n):
        for u in set(need[v]) - {start}:
            followers[u].append(v)
    open_ = np.zeros(n, dtype=bool)
    open_[(waiting == 0)] = True
    open_[start] = False
    order = [start]
    current = start
    for _ in range(n - 1):
        candidates = np.flatnonzero(open_)
        if candidates.size == 0:
            raise ValueError("the precedence constraints admit no order (they contain a cycle)")
        nxt = int(candidates[np.argmin(cost[current, candidates])])
        order.append(nxt)
        open_[nxt] = False
        for v in followers[nxt]:
            waiting[v] -= 1
            if waiting[v] == 0:
                open_[v] = True
        current = nxt
    return order


def repair_precedence(order: Sequence[int], need: Sequence[Sequence[int]], pull: bool = True) -> list[int]:
    """`order` made feasible while keeping its sequence where it can: a stop met before its required predecessors
    either pulls them in just before it (`pull`, good when predecessors sit near their followers), or waits and
    joins right after the last of them.

    >>> repair_precedence([0, 3, 1, 2], [[], [], [], [2]])
    [0, 2, 3, 1]
    >>> repair_precedence([0, 3, 1, 2], [[], [], [], [2]], pull=False)
    [0, 1, 2, 3]
    """
    if pull:
        return pull_forward(order, need)
    placed: set[int] = set()
    waiting: dict[int, list[int]] = {}
    missing = {v: len(set(need[v])) for v in order}
    out: list[int] = []

    def place(v: int) -> None:
        stack = [v]
        while stack:
            u = stack.pop()
            out.append(u)
            placed.add(u)
            released = []
            for w in waiting.pop(u, []):
                missing[w] -= 1
                if missing[w] == 0:
                    released.append(w)
            stack.extend(reversed(released))

    for v in order:
        absent = [u for u in set(need[v]) if u not in placed]
        if not absent:
            place(v)
            continue
        missing[v] = len(absent)
        for u in absent:
            waiting.setdefault(u, []).append(v)
    if len(out) != len(order):
        raise ValueError("the precedence constraints admit no order (they contain a cycle)")
    return out


def pull_forward(order: Sequence[int], need: Sequence[Sequence[int]], within: set[int] | None = None) -> list[int]:
    """`order` with every stop's missing predecessors pulled in just before it (recursively); predecessors
    outside `within`, when given, count as already placed.

    >>> pull_forward([3, 1, 2], [[], [], [], [2]])
    [2, 3, 1]
    """
    placed: set[int] = set()
    out: list[int] = []
    for v in order:
        if v in placed:
            continue
        if all(w in placed or (within is not None and w not in within) for w in need[v]):
            placed.add(v)
            out.append(v)
            continue
        stack: list[tuple[int, bool]] = [(v, False)]
        opened: set[int] = set()
        while stack:
            u, ready = stack.pop()
            if u in placed:
                continue
            if ready:
                placed.add(u)
                out.append(u)
                continue
            if u in opened:
                raise ValueError("the precedence constraints admit no order (they contain a cycle)")
            opened.add(u)
            stack.append((u, True))
            stack.extend((w, False) for w in reversed(need[u])
                         if w not in placed and (within is None or w in within))
    return out
