"""Maximum cliques of the consistency graph (seed 002 §3.2, made polynomial where it has to be).

A set of model/cloud pairs with agreeing distance sets is a clique of the consistency graph, so the seed's
largest coherent subset is a maximum clique. Three searches:

- `maximum_cliques`: exact branch and bound (Tomita's MCQ: greedy colouring gives the bound, vertices are
  expanded in colour order) returning *every* clique of the maximum size, since symmetric point sets have
  several. Exponential in the worst case, so a time budget (CPU seconds of the calling thread) guards it and the
  result says whether it finished.
- `maximal_cliques`: Bron–Kerbosch with pivoting and the same colouring bound, every maximal clique of at least
  `min_size` vertices (used when the largest cliques fail the rigid check), equally guarded.
- `dense_clique`: the polynomial fallback in the spirit of CLIPPER (Lusk et al., 2021): the leading eigenvector
  of the weighted consistency matrix refined by projected gradient ascent on uᵀ(W − d·(1 − A))u over the unit
  sphere's positive part, with a penalty d that grows; then a greedy extraction that adds vertices in
  decreasing u while they stay adjacent to all chosen ones. Cost: O(iterations · k²) for the ascent and
  O(seeds · k · ω) for the extraction on k vertices — polynomial, with no exactness guarantee.

>>> import numpy as np
>>> adj = np.zeros((6, 6), dtype=bool)
>>> for a, b in [(0, 1), (1, 2), (0, 2), (3, 4), (4, 5), (3, 5), (2, 3)]:
...     adj[a, b] = adj[b, a] = True
>>> maximum_cliques(adj).cliques
[[0, 1, 2], [3, 4, 5]]
>>> sorted(dense_clique(adj.astype(float), adj))
[0, 1, 2]
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]
BoolMatrix = NDArray[np.bool_]


@dataclass(frozen=True)
class CliqueSearch:
    """Cliques found (vertex lists, sorted, largest first) and whether the search finished within its budget."""

    cliques: list[list[int]]
    exact: bool


class _Budget(Exception):
    pass


def _bitsets(adjacency: BoolMatrix) -> list[int]:
    packed = np.packbits(np.asarray(adjacency, dtype=bool), axis=1, bitorder="little")
    return [int.from_bytes(row.tobytes(), "little") for row in packed]


def _members(bits: int) -> list[int]:
    out = []
    while bits:
        low = bits & -bits
        out.append(low.bit_length() - 1)
        bits ^= low
    return out


def _colour_order(candidates: int, nbrs: list[int]) -> tuple[list[int], list[int]]:
    """Greedy sequential colouring: vertices in colour-class order and, for each, its colour number (a bound on
    the clique size among it and the vertices before it)."""
    order: list[int] = []
    colours: list[int] = []
    uncoloured, colour = candidates, 0
    while uncoloured:
        colour += 1
        available = uncoloured
        while available:
            low = available & -available
            v = low.bit_length() - 1
            available &= ~nbrs[v] & ~low
            uncoloured &= ~low
            order.append(v)
            colours.append(colour)
    return order, colours


def maximum_cliques(adjacency: BoolMatrix, budget_s: float = 1.0, lower_bound: int = 0) -> CliqueSearch:
    """Every clique of maximum size (at least `lower_bound`), by colour-bounded branch and bound."""
    nbrs = _bitsets(adjacency)
    best: list[list[int]] = []
    size = [max(0, lower_bound)]
    deadline = time.thread_time() + budget_s

    def expand(clique: list[int], candidates: int) -> None:
        if time.thread_time() > deadline:
            raise _Budget
        order, colours = _colour_order(candidates, nbrs)
        for idx in range(len(order) - 1, -1, -1):
            if len(clique) + colours[idx] < size[0]:
                return                                  # ties are kept, so only strictly smaller branches go
            v = order[idx]
            grown = clique + [v]
            rest = candidates & nbrs[v]
            if rest:
                expand(grown, rest)
            elif len(grown) > size[0]:
                size[0], best[:] = len(grown), [sorted(grown)]
            elif len(grown) == size[0]:
                best.append(sorted(grown))
            candidates &= ~(1 << v)

    exact = True
    try:
        expand([], (1 << len(nbrs)) - 1)
    except _Budget:
        exact = False
    return CliqueSearch(cliques=sorted(best), exact=exact)


def maximal_cliques(adjacency: BoolMatrix, min_size: int = 3, budget_s: float = 1.0) -> CliqueSearch:
    """Every maximal clique with at least `min_size` vertices, largest first (Bron–Kerbosch, pivot, colour bound)."""
    nbrs = _bitsets(adjacency)
    found: list[list[int]] = []
    deadline = time.thread_time() + budget_s

    def extend(clique: list[int], candidates: int, excluded: int) -> None:
        if time.thread_time() > deadline:
            raise _Budget
        if not candidates:
            if not excluded and len(clique) >= min_size:
                found.append(sorted(clique))
            return
        if len(clique) + _colour_order(candidates, nbrs)[1][-1] < min_size:
            return
        pivot = max(_members(candidates | excluded), key=lambda u: (candidates & nbrs[u]).bit_count())
        for v in _members(candidates & ~nbrs[pivot]):
            bit = 1 << v
            extend(clique + [v], candidates & nbrs[v], excluded & nbrs[v])
            candidates &= ~bit
            excluded |= bit

    exact = True
    try:
        extend([], (1 << len(nbrs)) - 1, 0)
    except _Budget:
        exact = False
    return CliqueSearch(cliques=sorted(found, key=lambda c: (-len(c), c)), exact=exact)


def dense_clique(weights: Array, adjacency: BoolMatrix, iterations: int = 100, seeds: int = 8) -> list[int]:
    """A large clique in polynomial time (the CLIPPER-style fallback described in the module docstring)."""
    k = len(adjacency)
    if k == 0:
        return []
    A = np.asarray(adjacency, dtype=bool)
    W = np.where(A, np.asarray(weights, dtype=float), 0.0)
    np.fill_diagonal(W, 1.0)
    forbidden = (~A).astype(float)
    np.fill_diagonal(forbidden, 0.0)
    u = np.ones(k) / np.sqrt(k)
    for _ in range(20):                                  # power iteration: the leading eigenvector of W
        u = W @ u
        u /= max(np.linalg.norm(u), 1e-300)
    penalty, step = 1.0, 0.5
    for _ in range(iterations):
        grad = W @ u - penalty * (forbidden @ u)
        u_new = np.maximum(u + step * grad / max(np.abs(grad).max(), 1e-300), 0.0)
        norm = np.linalg.norm(u_new)
        if norm == 0.0:
            break
        u_new /= norm
        if np.abs(u_new - u).max() < 1e-6:
            penalty *= 2.0                               # converged for this penalty: tighten the constraint
        u = u_new
    ranking = np.argsort(-u, kind="stable")
    best: list[int] = []
    for seed in ranking[:seeds].tolist():
        chosen = [seed]
        common = A[seed].copy()
        for v in ranking.tolist():
            if common[v]:
                chosen.append(v)
                common &= A[v]
        if len(chosen) > len(best):
            best = chosen
    return sorted(best)
