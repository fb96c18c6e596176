"""Cost matrices and tours for the visiting-order problems of seed 002 §3.4 (the order of characteristic-point sets
and targets that minimises the distance travelled).

A cost matrix `cost[a, b]` is the cost of going from stop a to stop b (metres for the geometric problems). A tour
is a visiting order of stop indices starting with its start stop; a closed tour returns to the start, an open one
(a path) ends wherever it is cheapest.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]


@dataclass(frozen=True)
class Tour:
    """A visiting order. `order[0]` is the start; a closed tour returns from `order[-1]` to `order[0]` and that leg
    is included in `cost`. `exact` is True when dynamic programming proved the order optimal."""

    order: tuple[int, ...]
    cost: float
    closed: bool
    exact: bool = False


def distance_matrix(points: ArrayLike) -> Array:
    """Euclidean distances between the rows of `points` (n × 2 or n × 3).

    >>> distance_matrix([[0, 0], [3, 4]]).tolist()
    [[0.0, 5.0], [5.0, 0.0]]
    """
    p = np.asarray(points, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] not in (2, 3):
        raise ValueError(f"points must be an n × 2 or n × 3 array, got shape {p.shape}")
    diff = p[:, None, :] - p[None, :, :]
    return np.asarray(np.sqrt(np.einsum("ijk,ijk->ij", diff, diff)), dtype=np.float64)


def as_cost_matrix(cost: ArrayLike) -> Array:
    """`cost` as a float square matrix, checked: finite, non-negative off the diagonal."""
    c = np.array(cost, dtype=np.float64)
    if c.ndim != 2 or c.shape[0] != c.shape[1]:
        raise ValueError(f"a cost matrix must be square, got shape {c.shape}")
    if not np.all(np.isfinite(c)):
        raise ValueError("a cost matrix must be finite")
    off = ~np.eye(len(c), dtype=bool)
    if np.any(c[off] < 0):
        raise ValueError("a cost matrix must be non-negative")
    np.fill_diagonal(c, 0.0)
    return c


def is_symmetric(cost: Array) -> bool:
    return bool(np.allclose(cost, cost.T, rtol=1e-12, atol=1e-12 * (float(np.abs(cost).max()) + 1.0)))


def tour_cost(order: Sequence[int], cost: Array, closed: bool) -> float:
    """Cost of visiting `order` (returning to `order[0]` when `closed`).

    >>> tour_cost([0, 1, 2], np.array([[0, 1, 5], [1, 0, 2], [5, 2, 0]], dtype=float), closed=True)
    8.0
    """
    idx = np.asarray(order, dtype=np.int64)
    if len(idx) < 2:
        return 0.0
    total = float(cost[idx[:-1], idx[1:]].sum())
    return total + float(cost[idx[-1], idx[0]]) if closed else total


def neighbour_lists(cost: Array, k: int) -> list[list[int]]:
    """For each stop, the k others nearest to it (both directions of travel counted), nearest first."""
    n = len(cost)
    k = min(k, n - 1)
    sym = np.minimum(cost, cost.T).astype(np.float64)
    np.fill_diagonal(sym, np.inf)
    near = np.argpartition(sym, k - 1, axis=1)[:, :k] if k < n - 1 else np.argsort(sym, axis=1)[:, :k]
    rows = np.arange(n)[:, None]
    near = near[rows, np.argsort(sym[rows, near], axis=1, kind="stable")]
    return [[int(j) for j in row] for row in near]


def canonical(order: Sequence[int], start: int, closed: bool) -> tuple[int, ...]:
    """`order` rotated to begin at `start` (closed tours only; paths already do), as a tuple of ints."""
    seq = [int(v) for v in order]
    if closed:
        i = seq.index(start)
        seq = seq[i:] + seq[:i]
    return tuple(seq)


def dont_look_search(queued: bytearray | list[int], start: Iterable[int],
                     improve: Callable[[int], tuple[float, Iterable[int]] | None]) -> float:
    """Local search with don't-look bits: try `improve` from each queued stop; a stop is queued again only when a
    move touches one of its tour edges. `queued` is the per-stop flag array (0/1); returns the total gain."""
    todo: deque[int] = deque()
    for v in start:
        if not queued[v]:
            queued[v] = 1
            todo.append(v)
    total = 0.0
    while todo:
        a = todo.popleft()
        queued[a] = 0
        found = improve(a)
        if found is None:
            continue
        gain, touched = found
        total += gain
        for v in touched:
            if not queued[v]:
                queued[v] = 1
                todo.append(v)
    return total
