"""Structural coherence (seed 002 §3.1–3.2): pairwise distances and the consistency graph between a model's
characteristic points and a cloud.

The graph's nodes are candidate pairs (model i, cloud j); two nodes (i, j) and (k, l) are joined when i ≠ k,
j ≠ l and |d_model(i, k) − d_cloud(j, l)| ≤ tolerance. A set of pairs whose distance sets agree, which the seed
searches subset by subset, is exactly a clique of this graph.

All N·M pairs are nodes only for small problems: in a dense cloud every model distance recurs among the cloud's
distances, so the full graph of N = 20, M = 500 has ~10⁶ edges and its clique is invisible to spectral methods.
`signature_candidates` prunes without losing any clique of a given size (per-point distance signatures);
`perception_plugins.referencing.anchors` prunes to the pairs of well-supported placements.

>>> import numpy as np
>>> model = np.array([[0.0, 0, 0], [3, 0, 0], [0, 4, 0]])
>>> g = consistency_graph(model, model + 10.0, np.array([[0, 0], [1, 1], [2, 2], [0, 1]]), tolerance=0.01)
>>> g.adjacency.astype(int).tolist()
[[0, 1, 1, 0], [1, 0, 1, 0], [1, 1, 0, 0], [0, 0, 0, 0]]
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.distance import cdist

Array = NDArray[np.float64]
Index = NDArray[np.int64]


def distance_matrix(points: Array) -> Array:
    """All pairwise Euclidean distances (n, n) of points (n, 3).

    >>> distance_matrix(np.array([[0.0, 0, 0], [3, 4, 0]])).tolist()
    [[0.0, 5.0], [5.0, 0.0]]
    """
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    return np.asarray(cdist(pts, pts), dtype=float)


@dataclass(frozen=True)
class ConsistencyGraph:
    """Candidate pairs `nodes` (k, 2) = (model index, cloud index) and their symmetric boolean adjacency (k, k);
    `weights` (k, k) grade each edge by exp(−(Δd / tolerance)²), for the spectral fallback."""

    nodes: Index
    adjacency: NDArray[np.bool_]
    weights: Array

    @property
    def size(self) -> int:
        return int(len(self.nodes))

    @property
    def edge_count(self) -> int:
        return int(self.adjacency.sum()) // 2


def consistency_graph(model_points: Array, cloud_points: Array, nodes: Index, tolerance: float,
                      model_distances: Array | None = None, cloud_distances: Array | None = None
                      ) -> ConsistencyGraph:
    """The consistency graph over the given candidate pairs, built in one vectorised pass (k² entries)."""
    nodes = np.asarray(nodes, dtype=np.int64).reshape(-1, 2)
    dm = distance_matrix(model_points) if model_distances is None else model_distances
    dc = distance_matrix(cloud_points) if cloud_distances is None else cloud_distances
    i, j = nodes[:, 0], nodes[:, 1]
    diff = np.abs(dm[np.ix_(i, i)] - dc[np.ix_(j, j)])
    adjacency = (diff <= tolerance) & (i[:, None] != i[None, :]) & (j[:, None] != j[None, :])
    weights = np.where(adjacency, np.exp(-((diff / max(tolerance, 1e-12)) ** 2)), 0.0)
    return ConsistencyGraph(nodes=nodes, adjacency=adjacency, weights=weights)


def all_pairs(n_model: int, n_cloud: int) -> Index:
    """Every (model, cloud) pair: the nodes of the full graph."""
    ii, jj = np.meshgrid(np.arange(n_model), np.arange(n_cloud), indexing="ij")
    return np.stack([ii.ravel(), jj.ravel()], axis=1).astype(np.int64)


def signature_support(model_distances: Array, cloud_distances: Array, tolerance: float) -> NDArray[np.int64]:
    """support[i, j]: how many other model points k have some cloud point l ≠ j with
    |d_model(i, k) − d_cloud(j, l)| ≤ tolerance (the distance signature of point i found around point j)."""
    n, m = len(model_distances), len(cloud_distances)
    support = np.zeros((n, m), dtype=np.int64)
    rows = np.sort(cloud_distances, axis=1)[:, 1:]                  # drop the zero distance to itself
    for j in range(m):
        lo = np.searchsorted(rows[j], model_distances - tolerance, side="left")
        hi = np.searchsorted(rows[j], model_distances + tolerance, side="right")
        found = hi > lo
        np.fill_diagonal(found, False)
        support[:, j] = found.sum(axis=1)
    return support


def signature_candidates(model_distances: Array, cloud_distances: Array, tolerance: float,
                         min_clique: int) -> Index:
    """Pairs that can belong to a clique of at least `min_clique` nodes.

    A node of such a clique has neighbours with min_clique − 1 distinct model indices, so its signature support
    is at least that; the test is repeated on the surviving cloud points until nothing changes. Never loses a
    clique of that size; strong in sparse clouds, weak in dense ones.
    """
    keep_cloud = np.arange(len(cloud_distances))
    keep_model = np.arange(len(model_distances))
    while True:
        support = signature_support(model_distances[np.ix_(keep_model, keep_model)],
                                    cloud_distances[np.ix_(keep_cloud, keep_cloud)], tolerance)
        ok = support >= min_clique - 1
        cloud_ok, model_ok = ok.any(axis=0), ok.any(axis=1)
        if cloud_ok.all() and model_ok.all():
            break
        keep_cloud, keep_model = keep_cloud[cloud_ok], keep_model[model_ok]
        if len(keep_cloud) == 0 or len(keep_model) == 0:
            return np.zeros((0, 2), dtype=np.int64)
    ii, jj = np.nonzero(ok)
    return np.stack([keep_model[ii], keep_cloud[jj]], axis=1).astype(np.int64)
