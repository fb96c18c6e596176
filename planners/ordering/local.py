"""Local search for closed tours (the plain visiting-order problem of seed 002 §3.4): sequential 2-opt and 3-opt
moves in the Lin–Kernighan manner (take an edge out, put a shorter one in from its end, keep the running gain
positive), chained up to `depth` 3-opt moves deep, over neighbour lists with don't-look bits, and the double-bridge
kick of an iterated local search.

The tour is an array with positions; every move is made of reversals (2-opt flips) of the shorter side. A chain
that ends worse, or a rejected kick, is undone by restoring copies of the two arrays taken before it (two list
copies cost less than replaying the reversals backwards). Pure Python on lists: a move reads a handful of numbers,
where numpy's per-call overhead would dominate. Symmetric costs only.
"""

from __future__ import annotations

import random
import time
from collections.abc import Iterable, Sequence

from .costs import dont_look_search

EPS = 1e-9
Move = tuple[int, int, int, int, int, int, int]


class ClosedTour:
    """A closed tour `order` under moves; `cost[a][b]` as nested lists, `neighbours[a]` nearest first.

    `breadth` caps the candidates tried for the first and second added edge of a 3-opt move; `depth` is the
    longest chain of 3-opt moves tried from one stop."""

    def __init__(self, cost: list[list[float]], neighbours: Sequence[Sequence[int]], order: Sequence[int],
                 breadth: tuple[int, int] = (6, 5), depth: int = 6) -> None:
        self.cost = cost
        self.n = len(order)
        # each stop's candidates with their costs, nearest first: the inner loops read both
        self.near = [[(b, cost[a][b]) for b in nb[:breadth[0]]] for a, nb in enumerate(neighbours)]
        self.near5 = [[(b, cost[a][b]) for b in nb[:breadth[1]]] for a, nb in enumerate(neighbours)]
        self.depth = depth
        self.order = list(order)
        self.pos = [0] * self.n
        for i, v in enumerate(self.order):
            self.pos[v] = i
        self.queued = bytearray(self.n)

    def length(self) -> float:
        c, t = self.cost, self.order
        return sum(c[t[i - 1]][t[i]] for i in range(self.n))

    # -- reversals -------------------------------------------------------------------------------------------
    def flip(self, a: int, b: int, c: int, d: int) -> None:
        """Replace edges {a, b} and {c, d} by {a, c} and {b, d}; the cycle reads a b … c d one way or the other.
        Of the two paths whose reversal does it, the shorter is reversed."""
        t, pos, n = self.order, self.pos, self.n
        pa = pos[a] + 1
        if t[pa if pa < n else 0] == b:
            i, j = pos[b], pos[c]
        else:
            i, j = pos[c], pos[b]
        if 2 * ((j - i) % n + 1) > n:
            i, j = (j + 1) % n, (i - 1) % n
        if i <= j:
            seg = t[i:j + 1]
            seg.reverse()
            t[i:j + 1] = seg
            for k, v in enumerate(seg, i):
                pos[v] = k
            return
        cut = n - i                             # the path wraps: positions i…n−1, then 0…j
        seg = t[i:] + t[:j + 1]
        seg.reverse()
        t[i:] = seg[:cut]
        t[:j + 1] = seg[cut:]
        for k, v in enumerate(seg):
            pos[v] = k + i if k < cut else k - cut

    # -- moves -----------------------------------------------------------------------------------------------
    def search(self, t1: int, t2_only: int, gain: float, added: set[tuple[int, int]]) -> tuple[float, Move | None,
                                                                                                float, Move | None]:
        """The best sequential 2- or 3-opt move that removes an edge (t1, t2) and closes back at t1, and the best
        3-opt move left open (its last removed edge not yet closed) for the chain to go on from.

        t2 is next to t1 on the tour (either way round, `dr`; only `t2_only` if ≥ 0, when the removed edge's
        worth is `gain` instead of its length); t3 is a near neighbour of t2 with a positive running gain; t4 is
        next to t3: t4 before t3 closes as a 2-opt or goes on to t5 (near t4) and t6 on the side that keeps one
        cycle; t4 after t3 needs t5 between t2 and t3 (a segment exchange, both segments kept or reversed).
        Edges in `added` (put in earlier in the chain, both ways round) are not taken out again.
        Returns (gain, move, open gain, open move); a gain is the length removed minus the length added.
        """
        D, t, pos, n, near, near5 = self.cost, self.order, self.pos, self.n, self.near, self.near5
        Dt1 = D[t1]
        p1 = pos[t1]
        best = EPS
        move: Move | None = None
        best_open = 0.0
        open_move: Move | None = None
        for dr in (1, -1):
            t2 = t[(p1 + dr) % n]
            if t2_only >= 0 and t2 != t2_only:
                continue
            d12 = gain if t2_only >= 0 else Dt1[t2]
            p2 = pos[t2]
            for t3, d23 in near[t2]:
                g1 = d12 - d23
                if g1 <= 0.0:
                    break
                if t3 == t1:
                    continue
                p3 = pos[t3]
                o3 = ((p3 - p2) * dr) % n
                Dt3 = D[t3]
                t4 = t[(p3 - dr) % n]
                if t4 != t2 and not (added and (t3, t4) in added):
                    g2 = g1 + Dt3[t4]
                    g = g2 - Dt1[t4]
                    if g > best:
                        best, move = g, (0, t1, t2, t3, t4, 0, 0)
                    for t5, d45 in near5[t4]:
                        g3 = g2 - d45
                        if g3 <= best:
                            break
                        if t5 == t3 or t5 == t1:
                            continue
                        p5 = pos[t5]
                        if ((p5 - p2) * dr) % n < o3 - 1:
                            t6 = t[(p5 + dr) % n]
                            if t6 == t4:
                                continue
                        else:
                            t6 = t[(p5 - dr) % n]
                        if added and (t5, t6) in added:
                            continue
                        g4 = g3 + D[t5][t6]
                        g = g4 - Dt1[t6]
                        if g > best:
                            best, move = g, (1, t1, t2, t3, t4, t5, t6)
                        elif g4 > best_open:
                            best_open, open_move = g4, (1, t1, t2, t3, t4, t5, t6)
                t4 = t[(p3 + dr) % n]
                if t4 != t1 and not (added and (t3, t4) in added):
                    g2 = g1 + Dt3[t4]
                    for t5, d45 in near5[t4]:
                        g3 = g2 - d45
                        if g3 <= best:
                            break
                        p5 = pos[t5]
                        if ((p5 - p2) * dr) % n >= o3:
                            continue
                        t6 = t[(p5 + dr) % n]
                        if not (added and (t5, t6) in added):
                            g4 = g3 + D[t5][t6]
                            g = g4 - Dt1[t6]
                            if g > best:
                                best, move = g, (2, t1, t2, t3, t4, t5, t6)
                            elif g4 > best_open:
                                best_open, open_move = g4, (2, t1, t2, t3, t4, t5, t6)
                        if t5 != t2:
                            t6 = t[(p5 - dr) % n]
                            if not (added and (t5, t6) in added):
                                g4 = g3 + D[t5][t6]
                                g = g4 - Dt1[t6]
                                if g > best:
                                    best, move = g, (3, t1, t2, t3, t4, t5, t6)
                                elif g4 > best_open:
                                    best_open, open_move = g4, (3, t1, t2, t3, t4, t5, t6)
        return best, move, best_open, open_move

    def improve(self, t1: int) -> tuple[float, list[int]] | None:
        """Make an improving move from t1 if one is found: a 2- or 3-opt move, or a chain of up to `depth` 3-opt
        moves (Lin–Kernighan: each open move is made and the search goes on from its loose end, the running
        gain kept positive) that ends better than it started. Returns the gain and the stops touched."""
        gain, move, open_gain, open_move = self.search(t1, -1, 0.0, set())
        if move is not None:
            self.apply(move)
            return gain, list(move[1:5] if move[0] == 0 else move[1:])
        if self.depth < 2 or open_move is None:
            return None
        saved_order, saved_pos = self.order[:], self.pos[:]
        added: set[tuple[int, int]] = set()
        touched: list[int] = []
        for _ in range(1, self.depth):
            if open_move is None:
                break
            self.apply(open_move)
            _, _, t2, t3, t4, t5, t6 = open_move
            added.update(((t2, t3), (t3, t2), (t4, t5), (t5, t4)))
            touched.extend(open_move[1:])
            gain, move, open_gain, open_move = self.search(t1, t6, open_gain, added)
            if move is not None:
                self.apply(move)
                touched.extend(move[1:5] if move[0] == 0 else move[1:])
                return gain, touched
        self.order[:] = saved_order
        self.pos[:] = saved_pos
        return None

    def apply(self, move: Move) -> None:
        kind, t1, t2, t3, t4, t5, t6 = move
        if kind == 0:
            self.flip(t2, t1, t3, t4)
        elif kind == 1:
            self.flip(t2, t1, t3, t4)
            self.flip(t1, t4, t6, t5)
        elif kind == 2:
            self.flip(t1, t2, t3, t4)
            self.flip(t1, t3, t6, t5)
            self.flip(t3, t5, t2, t4)
        else:
            self.flip(t1, t2, t6, t5)
            self.flip(t2, t5, t3, t4)

    def optimise(self, start: Iterable[int]) -> float:
        """Improve until no move from a queued stop gains (don't-look bits: a stop is queued again only when
        one of its tour edges changes). Returns the total gain."""
        return dont_look_search(self.queued, start, self.improve)

    def double_bridge(self, i: int, l1: int, l2: int, l3: int) -> tuple[float, list[int]]:
        """The double-bridge kick on the three segments of lengths l1, l2, l3 after position i (A B C → C B A
        between their neighbours, no segment reversed). Returns the cost change and the stops touched."""
        t, n, D = self.order, self.n, self.cost
        p2, p3, p4 = i + l1, i + l1 + l2, i + l1 + l2 + l3
        a, b, c, d = t[i % n], t[(i + 1) % n], t[p2 % n], t[(p2 + 1) % n]
        e, f, g, h = t[p3 % n], t[(p3 + 1) % n], t[p4 % n], t[(p4 + 1) % n]
        delta = (D[a][f] + D[g][d] + D[e][b] + D[c][h]) - (D[a][b] + D[c][d] + D[e][f] + D[g][h])
        self.flip(a, b, g, h)
        self.flip(a, g, f, e)
        self.flip(g, e, d, c)
        self.flip(e, c, b, h)
        return delta, [a, b, c, d, e, f, g, h]


def iterated_local_search(tour: ClosedTour, rng: random.Random, kicks: int, max_segment: int,
                          deadline: float | None = None, fixed: tuple[int, int] | None = None) -> float:
    """Kick (double bridge with segments of 1…`max_segment` stops at a random place), re-optimise around the
    kick, keep the result if it is no worse, else restore the tour before it; `kicks` times or until `deadline`
    (perf_counter). An edge `fixed` is never kicked out. Returns the total gain over the starting tour."""
    n = tour.n
    total = tour.optimise(range(n))
    if n < 8:
        return total
    span = max(1, min(max_segment, (n - 2) // 3))
    fix = set(fixed) if fixed is not None else set()
    for k in range(kicks):
        if deadline is not None and (k & 15) == 0 and time.perf_counter() > deadline:
            break
        i = rng.randrange(n)
        l1, l2, l3 = rng.randint(1, span), rng.randint(1, span), rng.randint(1, span)
        if fix:
            t = tour.order
            cuts = (i, i + l1, i + l1 + l2, i + l1 + l2 + l3)
            if any({t[p % n], t[(p + 1) % n]} == fix for p in cuts):
                continue
        saved_order, saved_pos = tour.order[:], tour.pos[:]
        delta, touched = tour.double_bridge(i, l1, l2, l3)
        change = delta - tour.optimise(touched)
        if change <= EPS:
            total -= change
        else:
            tour.order[:] = saved_order
            tour.pos[:] = saved_pos
    return total
