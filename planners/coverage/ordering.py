"""Order of the cells (seed 002 §2.1: a path of minimal length through the survey; the same visiting-order
problem as the targets of §3.4, with each cell flyable in several ways).

Each task (a cell's meander, a contour pass) has variants (start side, direction); exactly one variant of every
task is flown. The order and variants minimise the transits between them, plus the approach from the start point
and the way to the finish point. Few tasks and variants: exact dynamic programming over subsets (Held–Karp).
More: greedy nearest neighbour, then 2-opt (reversing a stretch of tasks reverses each task's direction)
alternating with the best variants for the order found.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]
EXACT_MAX = 13
EXACT_WORK = 4e6          # at most about this many transit sums in the exact search (subsets × variants² / 2)


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
    return _greedy_two_opt(task_of, reverse_of, cost, start_cost, finish_cost)


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


def _greedy_two_opt(task_of: IntArray, reverse_of: IntArray, cost: Array, start_cost: Array,
                    finish_cost: Array) -> list[int]:
    n_tasks = int(task_of.max()) + 1
    left = set(range(n_tasks))
    v = int(np.argmin(start_cost))
    seq = [v]
    left.discard(int(task_of[v]))
    while left:
        mask = np.isin(task_of, list(left))
        cand = np.where(mask, cost[seq[-1]], np.inf)
        v = int(np.argmin(cand))
        seq.append(v)
        left.discard(int(task_of[v]))
    best = tour_cost(seq, cost, start_cost, finish_cost)
    for _ in range(20):
        improved = _or_opt(_two_opt(seq, reverse_of, cost, start_cost, finish_cost), reverse_of, cost, start_cost,
                           finish_cost)
        seq = _best_variants([int(task_of[v]) for v in improved], task_of, cost, start_cost, finish_cost)
        total = tour_cost(seq, cost, start_cost, finish_cost)
        if total >= best - 1e-9:
            break
        best = total
    return seq


def _or_opt(seq: list[int], reverse_of: IntArray, cost: Array, start_cost: Array, finish_cost: Array) -> list[int]:
    """Move single tasks (either way round) to where they cost least, while that shortens the tour."""

    def link(a: int | None, b: int | None) -> float:
        if a is None:
            return 0.0 if b is None else float(start_cost[b])
        return float(finish_cost[a]) if b is None else float(cost[a, b])

    seq = list(seq)
    improved = True
    while improved:
        improved = False
        for i in range(len(seq)):
            v = seq[i]
            prev = seq[i - 1] if i > 0 else None
            nxt = seq[i + 1] if i + 1 < len(seq) else None
            gain = link(prev, v) + link(v, nxt) - link(prev, nxt)
            rest = seq[:i] + seq[i + 1 :]
            best = (gain - 1e-9, -1, v)
            for j in range(len(rest) + 1):
                a = rest[j - 1] if j > 0 else None
                b = rest[j] if j < len(rest) else None
                for w in (v, int(reverse_of[v])):
                    add = link(a, w) + link(w, b) - link(a, b)
                    if add < best[0]:
                        best = (add, j, w)
            if best[1] >= 0:
                seq = rest[: best[1]] + [best[2]] + rest[best[1] :]
                improved = True
                break
    return seq


def _two_opt(seq: list[int], reverse_of: IntArray, cost: Array, start_cost: Array,
             finish_cost: Array) -> list[int]:
    seq = list(seq)
    n = len(seq)
    improved = True
    while improved:
        improved = False
        for i in range(n - 1):
            for j in range(i + 1, n):
                a, b = seq[i], seq[j]
                ra, rb = int(reverse_of[a]), int(reverse_of[b])
                before = (start_cost[a] if i == 0 else cost[seq[i - 1], a]) + (
                    finish_cost[b] if j == n - 1 else cost[b, seq[j + 1]])
                after = (start_cost[rb] if i == 0 else cost[seq[i - 1], rb]) + (
                    finish_cost[ra] if j == n - 1 else cost[ra, seq[j + 1]])
                if after < before - 1e-9:
                    seq[i : j + 1] = [int(reverse_of[v]) for v in reversed(seq[i : j + 1])]
                    improved = True
    return seq
