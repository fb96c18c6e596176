"""Order of the cells (seed 002 §2.1: a path of minimal length through the survey; the same visiting-order
problem as the targets of §3.4, with each cell flyable in several ways).

Each task (a cell's meander, a contour pass) has variants (start side, direction); exactly one variant of every
task is flown. The order and variants minimise the transits between them, plus the approach from the start point
and the way to the finish point. Few tasks and variants: exact dynamic programming over subsets (Held–Karp).
More: greedy nearest-neighbour tours from every variant, and the best few of them (with the one from the variant
nearest the start) refined by 2-opt (reversing a stretch of tasks reverses each task's direction) and or-opt
alternating with the best variants for the order found; the shortest wins.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]
EXACT_MAX = 13
EXACT_WORK = 4e6          # at most about this many transit sums in the exact search (subsets × variants² / 2)
STARTS = 3                # beyond the exact search, how many of the shortest greedy tours are refined too
TWO_OPT_MOVES = 4         # 2-opt moves at most, per task


def order_variants(
    task_of: IntArray, reverse_of: IntArray, cost: Array, start_cost: Array, finish_cost: Array
) -> list[int]:
    """Variant ids, one per task, in flying order, minimising start + transits + finish.

    `cost[a, b]` is the transit from the end of variant a to the start of variant b; `reverse_of[a]` is the variant
    flying a backwards (so `cost[reverse_of[b], reverse_of[a]] == cost[a, b]`).

    >>> cost = np.array([[0, 9, 1, 9], [9, 0, 9, 9], [9, 9, 0, 9], [9, 9, 9, 0]], dtype=float)
    >>> order_variants(np.array([0, 0, 1, 1]), np.array([1, 0, 3, 2]), cost, np.zeros(4), np.zeros(4))
    [0, 2]
    """
    n_tasks = int(task_of.max()) + 1
    if n_tasks == 1:
        return [int(np.argmin(start_cost + finish_cost))]
    if n_tasks <= EXACT_MAX and (1 << n_tasks) * len(task_of) ** 2 / 2 <= EXACT_WORK:
        return _held_karp(task_of, cost, start_cost, finish_cost)
    tours = _greedy_tours(task_of, cost)
    totals = start_cost[tours[:, 0]] + finish_cost[tours[:, -1]] + cost[tours[:, :-1], tours[:, 1:]].sum(axis=1)
    firsts: dict[tuple[int, ...], list[int]] = {}      # one tour per order of the tasks (the variants are re-chosen)
    for k in [int(np.argmin(start_cost)), *(int(k) for k in np.argsort(totals, kind="stable"))]:
        if len(firsts) > STARTS:
            break
        firsts.setdefault(tuple(int(t) for t in task_of[tours[k]]), [int(v) for v in tours[k]])
    return min((_improved(seq, task_of, reverse_of, cost, start_cost, finish_cost) for seq in firsts.values()),
               key=lambda seq: tour_cost(seq, cost, start_cost, finish_cost))


def tour_cost(seq: list[int], cost: Array, start_cost: Array, finish_cost: Array) -> float:
    total = float(start_cost[seq[0]] + finish_cost[seq[-1]])
    return total + float(sum(cost[a, b] for a, b in zip(seq[:-1], seq[1:], strict=True)))


def _held_karp(task_of: IntArray, cost: Array, start_cost: Array, finish_cost: Array) -> list[int]:
    """Exact: dp[mask, v] is the cheapest way to fly the tasks in `mask` ending with variant v; the masks are
    swept by number of tasks, every extension of a layer computed at once."""
    n_tasks = int(task_of.max()) + 1
    nv = len(task_of)
    full = (1 << n_tasks) - 1
    bit = (1 << task_of).astype(np.int64)
    dp = np.full((full + 1, nv), np.inf)
    parent = np.full((full + 1, nv), -1, dtype=np.int64)
    dp[bit, np.arange(nv)] = start_cost
    members = [np.flatnonzero(task_of == t) for t in range(n_tasks)]
    masks = np.arange(full + 1, dtype=np.int64)
    popcount = np.zeros(full + 1, dtype=np.int64)
    for t in range(n_tasks):
        popcount += (masks >> t) & 1
    for layer in range(1, n_tasks):
        in_layer = masks[popcount == layer]
        for t in range(n_tasks):
            sel = in_layer[((in_layer >> t) & 1) == 0]
            if sel.size == 0:
                continue
            vb = members[t]
            cand = dp[sel][:, :, None] + cost[None, :, vb]                  # (S, nv, |vb|)
            best = np.argmin(cand, axis=1)
            val = np.take_along_axis(cand, best[:, None, :], axis=1)[:, 0, :]
            new = sel | (1 << t)
            block = np.ix_(new, vb)
            better = val < dp[block]
            dp[block] = np.where(better, val, dp[block])
            parent[block] = np.where(better, best, parent[block])
    last = int(np.argmin(dp[full] + finish_cost))
    seq = []
    mask = full
    v = last
    while v >= 0:
        seq.append(v)
        prev = int(parent[mask, v])
        mask ^= int(bit[v])
        v = prev
    return seq[::-1]


def _best_variants(order: list[int], task_of: IntArray, cost: Array, start_cost: Array,
                   finish_cost: Array) -> list[int]:
    """For a fixed order of tasks, the variants minimising the tour (dynamic programming along the order)."""
    members = [np.flatnonzero(task_of == t) for t in order]
    acc = start_cost[members[0]].copy()
    back = []
    for k in range(1, len(members)):
        cand = acc[:, None] + cost[np.ix_(members[k - 1], members[k])]
        back.append(np.argmin(cand, axis=0))
        acc = cand.min(axis=0)
    j = int(np.argmin(acc + finish_cost[members[-1]]))
    seq = [int(members[-1][j])]
    for k in range(len(members) - 1, 0, -1):
        j = int(back[k - 1][j])
        seq.append(int(members[k - 1][j]))
    return seq[::-1]


def _greedy_tours(task_of: IntArray, cost: Array) -> IntArray:
    """Nearest-neighbour tours, one from every variant (row k starts with variant k): each next the variant of a
    task still to fly that is reached most cheaply (or at all: a task no transit reaches comes last). All grown at
    once.

    >>> cost = np.array([[0, 9, 1, 9], [9, 0, 9, 9], [9, 9, 0, 9], [9, 2, 9, 0]], dtype=float)
    >>> _greedy_tours(np.array([0, 0, 1, 1]), cost).tolist()
    [[0, 2], [1, 2], [2, 0], [3, 1]]
    """
    nv = len(task_of)
    rows = np.arange(nv)
    left = np.ones((nv, int(task_of.max()) + 1), dtype=bool)
    tours = [rows]
    left[rows, task_of] = False
    for _ in range(left.shape[1] - 1):
        nxt = np.argmin(np.where(left[:, task_of], np.minimum(cost[tours[-1]], 1e300), np.inf), axis=1)
        tours.append(nxt)
        left[rows, task_of[nxt]] = False
    return np.stack(tours, axis=1)


def _improved(seq: list[int], task_of: IntArray, reverse_of: IntArray, cost: Array, start_cost: Array,
              finish_cost: Array) -> list[int]:
    """`seq` after 2-opt and or-opt alternating with the best variants for the order, while that shortens it."""
    ext = _with_depot(cost, start_cost, finish_cost)
    flip = np.append(reverse_of, len(reverse_of))
    best = tour_cost(seq, cost, start_cost, finish_cost)
    for _ in range(20):
        improved = _or_opt(_two_opt(seq, flip, ext), flip, ext)
        seq = _best_variants([int(task_of[v]) for v in improved], task_of, cost, start_cost, finish_cost)
        total = tour_cost(seq, cost, start_cost, finish_cost)
        if total >= best - 1e-9:
            break
        best = total
    return seq


def _with_depot(cost: Array, start_cost: Array, finish_cost: Array) -> Array:
    """`cost` with a last row and column for a depot that every tour leaves for its start (`start_cost`) and
    returns to from its end (`finish_cost`), so that the local moves need no special ends.

    >>> _with_depot(np.array([[0.0, 1.0], [2.0, 0.0]]), np.array([3.0, 4.0]), np.array([5.0, 6.0])).tolist()
    [[0.0, 1.0, 5.0], [2.0, 0.0, 6.0], [3.0, 4.0, 0.0]]
    """
    n = len(cost)
    ext = np.zeros((n + 1, n + 1))
    ext[:n, :n] = cost
    ext[n, :n] = start_cost
    ext[:n, n] = finish_cost
    return ext


def _or_opt(seq: list[int], flip: IntArray, ext: Array) -> list[int]:
    """Move single tasks (either way round) to where they cost least, the best move first, while that shortens the
    tour (`ext` and `flip` with the depot, see `_with_depot`; every task and place weighed at once).

    >>> ext = _with_depot(np.abs(np.subtract.outer([0.0, 0.0, 2.0, 2.0, 1.0, 1.0], [0.0, 0.0, 2.0, 2.0, 1.0, 1.0])),
    ...                   np.array([0.0, 0.0, 5.0, 5.0, 5.0, 5.0]), np.zeros(6))     # tasks at 0, 2, 1; from 0
    >>> _or_opt([0, 2, 4], np.array([1, 0, 3, 2, 5, 4, 6]), ext)       # the task at 1 goes between 0 and 2
    [0, 4, 2]
    """
    depot = len(ext) - 1
    tour = np.array([depot, *seq, depot], dtype=np.int64)
    inner = np.arange(1, len(tour) - 1)
    for _ in range(len(tour) ** 2):
        v = tour[inner]
        gain = ext[tour[inner - 1], v] + ext[v, tour[inner + 1]] - ext[tour[inner - 1], tour[inner + 1]]
        a, b = tour[:-1], tour[1:]                                   # edge e joins tour[e] and tour[e + 1]
        add = np.stack([ext[a[None, :], w[:, None]] + ext[w[:, None], b[None, :]] - ext[a, b][None, :]
                        for w in (v, flip[v])])                      # (way, task, edge)
        edges = np.arange(len(a))
        touching = (edges[None, :] == inner[:, None] - 1) | (edges[None, :] == inner[:, None])
        change = np.where(touching[None], np.inf, add - gain[None, :, None])
        way, k, e = np.unravel_index(int(np.argmin(change)), change.shape)
        if not change[way, k, e] < -1e-9:
            break
        w = int(v[k] if way == 0 else flip[v[k]])
        rest = np.delete(tour, k + 1)
        tour = np.insert(rest, e + 1 if e < k + 1 else e, w)
    return [int(v) for v in tour[1:-1]]


def _two_opt(seq: list[int], flip: IntArray, ext: Array) -> list[int]:
    """Reverse stretches of the tour (each task flown the other way), the best first, while the transits at their
    ends shorten (`ext` and `flip` with the depot, see `_with_depot`; every stretch weighed at once). Those inside
    count as unchanged (the best variants are chosen afterwards); since a transit flown backwards need not cost the
    same, the moves could undo each other for ever: at most `TWO_OPT_MOVES` per task."""
    depot = len(ext) - 1
    tour = np.array([depot, *seq, depot], dtype=np.int64)
    n = len(tour)
    i, j = np.triu_indices(n - 2, 0)
    i, j = i + 1, j + 1                                            # reverse tour[i..j], 1 <= i <= j <= n - 2
    i, j = i[i < j], j[i < j]
    for _ in range(TWO_OPT_MOVES * n):
        before = ext[tour[i - 1], tour[i]] + ext[tour[j], tour[j + 1]]
        after = ext[tour[i - 1], flip[tour[j]]] + ext[flip[tour[i]], tour[j + 1]]
        k = int(np.argmin(after - before))
        if not after[k] - before[k] < -1e-9:
            break
        tour[i[k] : j[k] + 1] = flip[tour[i[k] : j[k] + 1][::-1]]
    return [int(v) for v in tour[1:-1]]
