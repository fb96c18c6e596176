"""Exact visiting order by dynamic programming over subsets (Held–Karp), with precedence constraints (seed 002
§3.4: a point set before the targets bound to it). Few stops only: the table has 2^m · m entries for m stops
besides the start.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .costs import Array, Tour

EXACT_MAX_STOPS = 12      # stops besides the start solved exactly by default
_HARD_MAX_STOPS = 20      # beyond this the table does not fit in memory


def held_karp(cost: Array, start: int = 0, closed: bool = True,
              precedences: Sequence[tuple[int, int]] = ()) -> Tour:
    """The cheapest order visiting every stop once from `start`, returning to it when `closed`, with each
    `(before, after)` pair of `precedences` respected. Works for asymmetric costs.

    dp[mask, j] is the cheapest path from the start through the stops in `mask` ending at j; masks are swept by
    size and, for each last stop j, every mask of a layer is extended at once. A mask whose stops include one
    whose predecessors are missing is never reached.

    >>> c = np.array([[0, 1, 9, 1], [1, 0, 1, 9], [9, 1, 0, 1], [1, 9, 1, 0]], dtype=float)
    >>> held_karp(c, 0, closed=True).cost
    4.0
    >>> held_karp(c, 0, closed=False, precedences=[(2, 1)]).order
    (0, 3, 2, 1)
    """
    n = len(cost)
    others = [v for v in range(n) if v != start]
    m = len(others)
    if m == 0:
        return Tour((start,), 0.0, closed, exact=True)
    if m > _HARD_MAX_STOPS:
        raise ValueError(f"exact ordering handles at most {_HARD_MAX_STOPS} stops besides the start, got {m}")
    index = {v: i for i, v in enumerate(others)}
    need = np.zeros(m, dtype=np.int64)          # bit mask of the stops that must come before each stop
    for before, after in precedences:
        if after == start and before != start:
            raise ValueError(f"stop {before} must precede the start {start}: infeasible")
        if before == start or before == after:
            continue
        need[index[after]] |= 1 << index[before]
    inner = cost[np.ix_(others, others)]
    size = 1 << m
    dp = np.full((size, m), np.inf)
    parent = np.full((size, m), -1, dtype=np.int8)
    firsts = np.flatnonzero(need == 0)
    dp[1 << firsts, firsts] = cost[start, np.asarray(others)[firsts]]
    masks = np.arange(size, dtype=np.int64)
    popcount = np.zeros(size, dtype=np.int64)
    for j in range(m):
        popcount += (masks >> j) & 1
    layers = [masks[popcount == k] for k in range(m + 1)]
    for k in range(2, m + 1):
        layer = layers[k]
        for j in range(m):
            bit = 1 << j
            sel = layer[((layer & bit) != 0) & ((layer & need[j]) == need[j])]
            if sel.size == 0:
                continue
            cand = dp[sel ^ bit] + inner[:, j][None, :]
            best = np.argmin(cand, axis=1)
            dp[sel, j] = cand[np.arange(sel.size), best]
            parent[sel, j] = best
    full = size - 1
    ends = dp[full] + (cost[np.asarray(others), start] if closed else 0.0)
    last = int(np.argmin(ends))
    if not np.isfinite(ends[last]):
        raise ValueError("the precedence constraints admit no order (they contain a cycle)")
    seq = []
    mask, j = full, last
    while j >= 0:
        seq.append(others[j])
        prev = int(parent[mask, j])
        mask ^= 1 << j
        j = prev
    return Tour((start, *seq[::-1]), float(ends[last]), closed, exact=True)
