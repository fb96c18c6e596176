"""Kicks and the iterated search for paths with precedence (seed 002 §3.4): every kick keeps each precedence, so
the search never leaves the feasible paths. Kicks: ruin-and-recreate (a stop and its nearest stops, or its
precedence partners, taken out and put back one by one at their cheapest feasible places), reversals of a random
stretch (often the open end or the first leg, which sets the path's direction) repaired by pulling predecessors
forward, and double bridges; a kicked path is kept when, re-optimised, it is within a small slack of the best
(record-to-record travel).
"""

from __future__ import annotations

import random
import time

from .construct import pull_forward
from .precedence import EPS, PrecedencePath, changed_edges

REVERSE_SHARE = 0.15  # share of kicks that reverse a random stretch (repaired to keep precedence)
RUIN_SHARE = 0.5      # share of kicks that are ruin-and-recreate (the rest are double bridges)
RUIN_MAX = 10         # most stops a ruin takes out


def double_bridge(path: PrecedencePath, i: int, l1: int, l2: int, l3: int) -> tuple[float, list[int]] | None:
    """Segments A B C after position i become C B A, if that keeps every precedence; returns the cost change
    and the stops touched, or None (nothing changed)."""
    o, C = path.order, path.cost
    j = i + l1 + l2 + l3
    seg_a, seg_b, seg_c = o[i + 1:i + 1 + l1], o[i + 1 + l1:i + 1 + l1 + l2], o[i + 1 + l1 + l2:j + 1]
    later = set(seg_b) | set(seg_c)
    for x in seg_a:
        if any(w in later for w in path.follow[x]):
            return None
    for x in seg_b:
        if any(w in seg_c for w in path.follow[x]):
            return None
    x, y = o[i], o[j + 1]
    delta = (C[x][seg_c[0]] + C[seg_c[-1]][seg_b[0]] + C[seg_b[-1]][seg_a[0]] + C[seg_a[-1]][y]) - (
        C[x][seg_a[0]] + C[seg_a[-1]][seg_b[0]] + C[seg_b[-1]][seg_c[0]] + C[seg_c[-1]][y])
    o[i + 1:j + 1] = seg_c + seg_b + seg_a
    path.reindex(i + 1, j)
    return delta, [x, y, seg_a[0], seg_a[-1], seg_b[0], seg_b[-1], seg_c[0], seg_c[-1]]


def reverse_repair(path: PrecedencePath, x: int, y: int) -> tuple[float, list[int]]:
    """Reverse positions x..y, pulling forward any predecessor the reversal puts after its follower (a set
    goes back just before its first target). Returns the cost change and the stops touched."""
    o = path.order
    before = path.length()
    old = o[x - 1:y + 2]
    o[x:y + 1] = pull_forward(old[-2:0:-1], path.need, set(old[1:-1]))
    path.reindex(x, y)
    return path.length() - before, changed_edges(old, o[x - 1:y + 2])


def ruin_recreate(path: PrecedencePath, seed_stop: int, size: int,
                  rng: random.Random) -> tuple[float, list[int]] | None:
    """Take out `seed_stop` and its nearest stops (`size` in all; half the time its precedence partners
    first), then put each back at the cheapest place between its predecessors already on the path and its
    followers already on it (looked for next to its near stops, else anywhere allowed), in a random order that
    puts predecessors back first (so that constraints passing through stops still out cannot be broken).
    Returns the cost change and the stops touched."""
    o, C, near = path.order, path.cost, path.near
    out = [seed_stop]
    related = path.need[seed_stop] + path.follow[seed_stop] if rng.random() < 0.5 else []
    for v in related + near[seed_stop]:
        if len(out) >= size:
            break
        if 0 < path.pos[v] < len(o) - 1 and v not in out:
            out.append(v)
    gone = set(out)
    rng.shuffle(out)
    queue: list[int] = []
    while out:                                  # random topological order of the stops taken out
        v = next(u for u in out if not any(w in gone and w not in queue for w in path.need[u]))
        out.remove(v)
        queue.append(v)
    before = path.length()
    keep = [v for v in o if v not in gone]
    present = set(keep)
    touched: list[int] = []
    for v in queue:
        lo = max((keep.index(u) for u in path.need[v] if u in present), default=0)
        hi = min((keep.index(w) for w in path.follow[v] if w in present), default=len(keep) - 1)
        hi = min(hi, len(keep) - 1)
        spots: set[int] = set()                 # next to a near stop, where a cheap place usually is
        for u in near[v]:
            if u in present:
                k = keep.index(u)
                spots.update((k - 1, k))
        tries = [k for k in spots if lo <= k < hi] or range(lo, hi)
        row_in = C[v]
        best_k, best_c = -1, float("inf")
        for k in tries:
            a, b = keep[k], keep[k + 1]
            extra = C[a][v] + row_in[b] - C[a][b]
            if extra < best_c:
                best_k, best_c = k, extra
        if best_k < 0:
            return None                         # cannot happen on a feasible path; leave it unchanged
        keep.insert(best_k + 1, v)
        present.add(v)
        touched.extend((keep[best_k], v, keep[best_k + 2]))
    o[:] = keep
    path.reindex(0, len(o) - 1)
    return path.length() - before, touched


def iterated_precedence_search(path: PrecedencePath, rng: random.Random, kicks: int, max_segment: int,
                               deadline: float | None = None, slack: float = 0.0) -> float:
    """Iterated local search on a feasible path: kick, re-optimise, keep the result if it is within `slack`
    (a fraction) of the best path so far (record-to-record travel; 0 keeps only paths no worse than the
    current one), else restore. Ends on the best path found; returns the total gain over the starting path."""
    m = len(path.order)
    start_length = path.length()
    path.optimise(range(m))
    current = path.length()
    best, best_order = current, path.order[:]
    inner = m - 2                                   # stops between the fixed start and the end sentinel
    span = max(1, min(max_segment, inner // 3))
    for k in range(kicks if inner >= 4 else 0):
        if deadline is not None and (k & 15) == 0 and time.perf_counter() > deadline:
            break
        saved = path.order[:]
        draw = rng.random()
        kicked: tuple[float, list[int]] | None
        if draw < REVERSE_SHARE:
            x = rng.randrange(1, m - 2)
            y = rng.randrange(x + 1, m - 1)
            if rng.random() < 0.5:                  # the open end or the first leg: the path's direction
                x, y = (x, m - 2) if rng.random() < 0.5 else (1, y)
            kicked = reverse_repair(path, x, y)
        elif draw < REVERSE_SHARE + RUIN_SHARE:
            kicked = ruin_recreate(path, path.order[rng.randrange(1, m - 1)], rng.randint(2, RUIN_MAX), rng)
        else:
            l1, l2, l3 = rng.randint(1, span), rng.randint(1, span), rng.randint(1, span)
            if l1 + l2 + l3 > inner:
                continue
            i = rng.randrange(0, inner - (l1 + l2 + l3) + 1)
            kicked = double_bridge(path, i, l1, l2, l3)
        if kicked is None:
            continue
        delta, touched = kicked
        candidate = current + delta - path.optimise(touched)
        if candidate <= current + EPS or candidate <= best * (1.0 + slack):
            current = candidate
            if current < best - EPS:
                best, best_order = current, path.order[:]
        else:
            path.order[:] = saved
            path.reindex(0, m - 1)
    if current > best + EPS:
        path.order[:] = best_order
        path.reindex(0, m - 1)
    return start_length - best
