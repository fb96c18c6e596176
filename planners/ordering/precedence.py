"""Paths with precedence (seed 002 §3.4: a characteristic-point set is visited before the targets referenced to
it): feasibility checks and a local search whose moves keep every precedence, so no order it returns violates one.

The path starts at a fixed stop and ends at a zero-cost sentinel `end` (an open end: the path may finish anywhere).
Moves: Or-opt (a segment of 1…3 stops moved elsewhere, reversed too when costs are symmetric), exchanges of two
neighbouring segments of any length (Or-3opt, nothing reversed) and 2-opt reversals (symmetric costs; a reversal
that would put a target before its set is repaired by pulling the set forward and priced again), each checked
against the precedences by positions before it is taken. The kicks and the iterated search are in `kicks`.

The precedence graph is checked for cycles by Kahn's algorithm on the need/follow lists the search uses; only when
it finds one does networkx name it (`find_cycle`). Measured (`benchmarks/networkx_timing.py`): building a
`networkx.DiGraph` and testing it with `is_directed_acyclic_graph` takes 4.5–7.6× as long as the lists and Kahn's
check (30–300 stops: 66–850 µs against 9–133 µs; either is under 0.1 % of a `solve_precedence` call), so the
lists stay and networkx only names a cycle for the error message.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

from .construct import pull_forward
from .costs import dont_look_search

EPS = 1e-9
EXCHANGE_BREADTH = 6  # candidates tried for each added edge of a segment exchange
OROPT_BREADTH = 6     # candidates tried for the stops a moved segment is put between
REPAIR_MAX = 30       # longest reversal repaired when it breaks a precedence


def violations(order: Sequence[int], precedences: Iterable[tuple[int, int]]) -> int:
    """How many `(before, after)` pairs `order` breaks (a stop missing from `order` breaks its pairs).

    >>> violations([0, 2, 1], [(1, 2), (0, 1)])
    1
    """
    pos = {v: i for i, v in enumerate(order)}
    return sum(1 for b, a in precedences if b not in pos or a not in pos or pos[b] > pos[a])


def precedence_cycle(n: int, need: Sequence[Sequence[int]]) -> list[int] | None:
    """A cycle of the precedence graph over stops 0…n−1 (`need[v]`: the stops that must precede v), as the stops
    along it, or None when the graph has none (Kahn's algorithm; networkx names the cycle).

    >>> precedence_cycle(4, [[], [3], [1], [2]]), precedence_cycle(3, [[], [0], [0, 1]])
    ([1, 2, 3], None)
    """
    waiting = [len(set(v)) for v in need]
    follow: list[list[int]] = [[] for _ in range(n)]
    for v in range(n):
        for u in set(need[v]):
            follow[u].append(v)
    ready = [v for v in range(n) if waiting[v] == 0]
    done = 0
    while ready:
        u = ready.pop()
        done += 1
        for w in follow[u]:
            waiting[w] -= 1
            if waiting[w] == 0:
                ready.append(w)
    if done == n:
        return None
    import networkx as nx

    graph = nx.DiGraph([(u, v) for v in range(n) if waiting[v] > 0 for u in need[v] if waiting[u] > 0])
    cycle = [u for u, _ in nx.find_cycle(graph)]
    first = cycle.index(min(cycle))
    return cycle[first:] + cycle[:first]


def changed_edges(old: Sequence[int], new: Sequence[int]) -> list[int]:
    """The stops of `new` (a stretch of path) whose path edges differ from those they had in `old`."""
    edges = {frozenset(e) for e in zip(old, old[1:], strict=False)}
    touched: list[int] = []
    for a, b in zip(new, new[1:], strict=False):
        if frozenset((a, b)) not in edges:
            touched += (a, b)
    return touched


class PrecedencePath:
    """A path `order` (fixed first stop, sentinel `end` last) under precedence-keeping moves. `need[v]` are the
    stops that must precede v, `follow[v]` those that must come after it."""

    def __init__(self, cost: list[list[float]], neighbours: Sequence[Sequence[int]], order: Sequence[int],
                 need: Sequence[Sequence[int]], follow: Sequence[Sequence[int]], symmetric: bool,
                 max_segment: int = 3) -> None:
        self.cost = cost
        self.near = [list(nb) for nb in neighbours]
        self.order = list(order)
        self.pos = [0] * len(self.order)
        self.reindex(0, len(self.order) - 1)
        self.need = [list(v) for v in need]
        self.follow = [list(v) for v in follow]
        self.symmetric = symmetric
        self.max_segment = max_segment
        self.queued = bytearray(len(self.order))

    def reindex(self, i: int, j: int) -> None:
        """Refresh the positions of the stops at positions i..j."""
        o, pos = self.order, self.pos
        for k in range(i, j + 1):
            pos[o[k]] = k

    def length(self) -> float:
        c, o = self.cost, self.order
        return sum(c[o[k]][o[k + 1]] for k in range(len(o) - 1))

    # -- feasibility by positions ----------------------------------------------------------------------------
    def _no_pair_inside(self, i: int, j: int) -> bool:
        o, pos, follow = self.order, self.pos, self.follow
        for k in range(i, j + 1):
            for w in follow[o[k]]:
                if i <= pos[w] <= j:
                    return False
        return True

    def _can_move(self, i: int, j: int, pu: int) -> bool:
        """Can the segment at positions i..j go between positions pu and pu + 1 (order kept)?"""
        o, pos = self.order, self.pos
        if pu > j:
            for k in range(i, j + 1):
                for w in self.follow[o[k]]:
                    if j < pos[w] <= pu:
                        return False
        else:
            for k in range(i, j + 1):
                for w in self.need[o[k]]:
                    if pu < pos[w] < i:
                        return False
        return True

    # -- moves -----------------------------------------------------------------------------------------------
    def best_move(self, a: int) -> tuple[float, tuple[int, ...]] | None:
        C, o, pos, near = self.cost, self.order, self.pos, self.near
        m = len(o)
        pa = pos[a]
        best, move = self._exchange(a, EPS, None)
        if pa == 0 or pa == m - 1:
            return None if move is None else (best, move)
        sym = self.symmetric
        for length in range(1, self.max_segment + 1):
            for i in (pa,) if length == 1 else (pa, pa - length + 1):
                j = i + length - 1
                if i < 1 or j > m - 2:
                    continue
                s1, s2, p, nx = o[i], o[j], o[i - 1], o[j + 1]
                g0 = C[p][s1] + C[s2][nx] - C[p][nx]
                if g0 <= best:
                    continue
                reversible = -1                     # unknown until a reversed insertion is worth checking
                for end_ in (s1, s2):
                    for c in near[end_][:OROPT_BREADTH]:
                        pc = pos[c]
                        if i <= pc <= j or pc == m - 1:
                            continue
                        # c before the segment end: u = c, v = o[pc + 1]; the near end joins c
                        if c != p and pc + 1 <= m - 1:
                            v = o[pc + 1]
                            if end_ == s1:
                                g = g0 - (C[c][s1] + C[s2][v] - C[c][v])
                                rev = False
                            else:
                                g = g0 - (C[c][s2] + C[s1][v] - C[c][v])
                                rev = True
                            if g > best and (not rev or sym):
                                if rev and reversible < 0:
                                    reversible = int(self._no_pair_inside(i, j))
                                if (not rev or reversible) and self._can_move(i, j, pc):
                                    best, move = g, (1, i, j, pc, int(rev))
                        # c after the segment: u = o[pc - 1], v = c; the near end joins c
                        if c != nx and pc >= 1:
                            u = o[pc - 1]
                            if end_ == s2:
                                g = g0 - (C[u][s1] + C[s2][c] - C[u][c])
                                rev = False
                            else:
                                g = g0 - (C[u][s2] + C[s1][c] - C[u][c])
                                rev = True
                            if g > best and (not rev or sym):
                                if rev and reversible < 0:
                                    reversible = int(self._no_pair_inside(i, j))
                                if (not rev or reversible) and self._can_move(i, j, pc - 1):
                                    best, move = g, (1, i, j, pc - 1, int(rev))
                    if length == 1:
                        break
        if sym:
            b = o[pa + 1]
            d_ab = C[a][b]
            pred = o[pa - 1]
            d_pa = C[pred][a]
            for c in near[a]:
                g1 = d_ab - C[a][c]
                g2 = d_pa - C[a][c]
                if g1 <= best and g2 <= best:
                    break
                pc = pos[c]
                if pc == m - 1:
                    continue
                if g1 > best:                     # edge (a, b) out, (a, c) in
                    if pc > pa + 1:
                        d = o[pc + 1]
                        best, move = self._reversal(pa + 1, pc, g1 + C[c][d] - C[b][d], best, move)
                    elif pc < pa - 1:
                        e = o[pc + 1]
                        best, move = self._reversal(pc + 1, pa, g1 + C[c][e] - C[e][b], best, move)
                if g2 > best:                     # edge (pred, a) out, (a, c) in
                    if pc > pa + 1:
                        e = o[pc - 1]
                        best, move = self._reversal(pa, pc - 1, g2 + C[e][c] - C[pred][e], best, move)
                    elif 1 <= pc < pa - 1:
                        e = o[pc - 1]
                        best, move = self._reversal(pc, pa - 1, g2 + C[e][c] - C[e][pred], best, move)
        return None if move is None else (best, move)

    def _reversal(self, x: int, y: int, gain: float, best: float,
                  move: tuple[int, ...] | None) -> tuple[float, tuple[int, ...] | None]:
        """A 2-opt reversal of positions x..y worth `gain`, if it beats `best`. When the reversal would put a stop
        before one of its predecessors inside it, the reversed stretch is repaired by pulling those predecessors
        forward (a set goes back just before its first target) and priced again."""
        if gain <= best:
            return best, move
        if self._no_pair_inside(x, y):
            return gain, (2, x, y)
        if y - x >= REPAIR_MAX:
            return best, move
        o, C = self.order, self.cost
        seg = o[x:y + 1]
        fixed = pull_forward(seg[::-1], self.need, set(seg))
        old = C[o[x - 1]][seg[0]] + C[seg[-1]][o[y + 1]] + sum(C[u][v] for u, v in zip(seg, seg[1:], strict=False))
        new = C[o[x - 1]][fixed[0]] + C[fixed[-1]][o[y + 1]] + sum(
            C[u][v] for u, v in zip(fixed, fixed[1:], strict=False))
        if old - new > best:
            return old - new, (4, x, y, *fixed)
        return best, move

    def _exchange(self, a: int, best: float, move: tuple[int, ...] | None) -> tuple[float, tuple[int, ...] | None]:
        """The best exchange of two neighbouring segments (x A B y → x B A y, neither reversed: Or-3opt) with a
        as x (its new neighbour B0 near it) or as y (its new neighbour A_end near it)."""
        C, o, pos, near = self.cost, self.order, self.pos, self.near
        m = len(o)
        pa = pos[a]
        width = EXCHANGE_BREADTH
        if pa <= m - 4:                                  # a = x
            a0 = o[pa + 1]
            d_xa = C[a][a0]
            for b0 in near[a][:width]:
                g1 = d_xa - C[a][b0]
                if g1 <= 0.0:
                    break
                j = pos[b0]
                if j <= pa + 1 or j == m - 1:
                    continue
                a_end = o[j - 1]
                g2 = g1 + C[a_end][b0]
                for b_end in near[a0][:width]:
                    k = pos[b_end]
                    if k < j or k >= m - 1:
                        continue
                    y = o[k + 1]
                    g = g2 + C[b_end][y] - C[b_end][a0] - C[a_end][y]
                    if g > best and self._can_move(pa + 1, j - 1, k):
                        best, move = g, (3, pa + 1, j, k)
        if pa >= 3:                                      # a = y
            b_end = o[pa - 1]
            d_by = C[b_end][a]
            for a_end in near[a][:width]:
                g1 = d_by - C[a_end][a]
                if g1 <= 0.0:
                    break
                r = pos[a_end]
                if r >= pa - 1 or r < 1:
                    continue
                b0 = o[r + 1]
                g2 = g1 + C[a_end][b0]
                for a0 in near[b_end][:width]:
                    i = pos[a0]
                    if i < 1 or i > r:
                        continue
                    x = o[i - 1]
                    g = g2 + C[x][a0] - C[b_end][a0] - C[x][b0]
                    if g > best and self._can_move(i, r, pa - 1):
                        best, move = g, (3, i, r + 1, pa - 1)
        return best, move

    def apply(self, move: tuple[int, ...]) -> list[int]:
        """Make `move`; returns the stops whose path edges changed."""
        o = self.order
        if move[0] == 4:                                 # positions x..y reversed and repaired
            x, y = move[1], move[2]
            old = o[x - 1:y + 2]
            o[x:y + 1] = list(move[3:])
            self.reindex(x, y)
            return changed_edges(old, o[x - 1:y + 2])
        if move[0] == 3:                                 # segments i..j-1 and j..k exchanged
            _, i, j, k = move
            touched = [o[i - 1], o[i], o[j - 1], o[j], o[k], o[k + 1]]
            o[i:k + 1] = o[j:k + 1] + o[i:j]
            self.reindex(i, k)
            return touched
        if move[0] == 2:
            _, i, j = move
            touched = [o[i - 1], o[i], o[j], o[j + 1]]
            o[i:j + 1] = o[i:j + 1][::-1]
            self.reindex(i, j)
            return touched
        _, i, j, pu, rev = move
        seg = o[i:j + 1][::-1] if rev else o[i:j + 1]
        touched = [o[i - 1], o[i], o[j], o[j + 1], o[pu], o[pu + 1]]
        if pu > j:
            o[i:pu + 1] = o[j + 1:pu + 1] + seg
            self.reindex(i, pu)
        else:
            o[pu + 1:j + 1] = seg + o[pu + 1:i]
            self.reindex(pu + 1, j)
        return touched

    def optimise(self, start: Iterable[int]) -> float:
        """Apply the best precedence-keeping move from each queued stop until none gains (don't-look bits)."""

        def improve(a: int) -> tuple[float, list[int]] | None:
            found = self.best_move(a)
            if found is None:
                return None
            gain, move = found
            return gain, self.apply(move)

        return dont_look_search(self.queued, start, improve)
