"""Identification of a model's characteristic points in a 3D cloud and referencing to the object
(seed 002 §3.1–3.3): the public API.

1. Candidate pairs: every (model, cloud) pair for small problems (pruned by distance signatures, which loses no
   clique), otherwise the pairs of the best placements that anchor triangles give (`anchors`).
2. The consistency graph on them (`consistency`) and its largest cliques (`clique`): exact branch and bound
   within a time budget, the polynomial CLIPPER-style extraction when that runs out.
3. Every clique is checked before acceptance (distances alone cannot tell a set from its mirror image, and
   outliers fake small coherent sets): a proper rigid fit (det = +1) whose pairs all lie within `tolerance`
   (a quarter of a clique of five or more may be rejected as wrong pairs), points spread out of a line, and a
   maximal clique (a subset of a clique that failed is no identification). Model points that the fit puts within
   `tolerance` of an unused cloud point are added (pairs whose edges noise broke), and a pair is dropped again
   if the set fits markedly better without it (the MSAC score rises: the fit had leaned towards an outlier).
4. Sets are ranked by their MSAC score Σ max(0, 1 − (r / tolerance)²): the number of pairs, each counted for
   how well it fits, so a larger set wins unless it fits markedly worse (in a dense cloud a chance set can be a
   point larger than a small true one). Sets within MARGIN of the best score and with different transforms are
   equally consistent (a symmetric set such as a rectangle's corners); the prior transform, if given, tells them
   apart: the one closest to it (rotation angle × the model's RMS radius + displacement of the model centroid)
   is chosen, and the result is ambiguous unless it is at most half as far from the prior as the next one. A
   three-point set with equally good alternatives is recognised only when the prior picks it clearly (any
   three points fit some triangle of a dense cloud).
5. Fewer than three identified points means "not recognised" (§3.3); the transform is the least-squares one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from perception_plugins.referencing.anchors import search_placements
from perception_plugins.referencing.clique import CliqueSearch, dense_clique, maximal_cliques, maximum_cliques
from perception_plugins.referencing.consistency import (
    ConsistencyGraph,
    consistency_graph,
    distance_matrix,
    signature_candidates,
)
from perception_plugins.referencing.transform import (
    apply,
    is_degenerate,
    msac_score,
    rigid_transform,
    rigid_transforms,
    robust_rigid_transform,
    rotation_angle_deg,
)

Array = NDArray[np.float64]

FULL_GRAPH_PAIRS = 400           # up to N·M pairs the graph holds every pair (before signature pruning)
PLACEMENTS_KEPT = 48             # best anchor placements whose pairs become candidates
EXACT_CLIQUE_NODES = 2000        # larger candidate graphs go straight to the polynomial clique fallback
CLEAR_CUT = 0.5                  # the chosen identification must be this much closer to the prior than the next
MARGIN = 0.5                     # identifications within this MSAC score of the best are equally consistent


@dataclass(frozen=True)
class Identification:
    """One accepted identification: pairs (model index, cloud index), transform model → cloud, RMS residual and
    MSAC score of the residuals."""

    pairs: list[tuple[int, int]]
    T_cloud_model: Array
    residual_rms: float
    score: float


@dataclass(frozen=True)
class Referencing:
    """The outcome of referencing a characteristic-point set in a cloud.

    `recognised`: at least three points identified (seed 002 §3.3). `T_cloud_model` maps model (object-frame)
    coordinates to cloud (camera) coordinates; None when not recognised. `ambiguous`: several equally consistent
    identifications remained and the prior (or its absence) could not separate them; `alternatives`: how many
    others there were besides the chosen one. `exact`: every search finished within its budget.
    """

    recognised: bool
    pairs: list[tuple[int, int]]
    T_cloud_model: Array | None
    residual_rms: float
    matched: int
    ambiguous: bool
    alternatives: int
    exact: bool = True
    candidates: int = 0
    method: str = ""
    identifications: list[Identification] = field(default_factory=list, repr=False)


def identify(model_points: Array, cloud_points: Array, tolerance: float) -> list[tuple[int, int]]:
    """Pairs (model index, cloud index) of the model's characteristic points found in the cloud; empty when
    fewer than three are identified. For symmetric sets use `reference` with a prior.

    >>> model = np.array([[0.0, 0, 0], [4, 0, 0], [0, 3, 0], [0, 0, 2], [3, 3, 1]])
    >>> cloud = np.vstack([[9.0, 9, 9], [5, -3, 2], model[[2, 0, 3, 1]] + [1.0, 2, 3]])
    >>> identify(model, cloud, tolerance=0.05)
    [(0, 3), (1, 5), (2, 2), (3, 4)]
    """
    return reference(model_points, cloud_points, tolerance).pairs


def reference(model_points: Array, cloud_points: Array, tolerance: float,
              prior_T_cloud_model: Array | None = None, budget_s: float = 3.0) -> Referencing:
    """Identify the model's points in the cloud and compute T_cloud_model (see the module docstring).

    `budget_s` bounds the searches in CPU seconds of the calling thread (so that a loaded machine does not
    change the result); past it the best found so far is used and `exact` is False.
    """
    model = _points(model_points, "model_points")
    cloud = _points(cloud_points, "cloud_points")
    if tolerance <= 0:
        raise ValueError(f"tolerance must be positive, got {tolerance}")
    if len(model) < 3 or len(cloud) < 3:
        return _not_recognised(exact=True, candidates=0, method="too few points")
    found, exact, candidates, method = _identifications(model, cloud, float(tolerance), budget_s)
    if not found:
        return _not_recognised(exact, candidates, method)
    equal = [f for f in found if f.score >= found[0].score - MARGIN]
    chosen, ambiguous = _choose(equal, model, prior_T_cloud_model)
    if len(chosen.pairs) == 3 and len(equal) > 1 and ambiguous:
        # Three points fit several ways (a right triangle of a rectangle's corners): only a clear-cut prior
        # may pick one; without it, the set is not recognised.
        return _not_recognised(exact, candidates, method + ": three-point set not unique")
    return Referencing(recognised=True, pairs=chosen.pairs, T_cloud_model=chosen.T_cloud_model,
                       residual_rms=chosen.residual_rms, matched=len(chosen.pairs), ambiguous=ambiguous,
                       alternatives=len(equal) - 1, exact=exact, candidates=candidates, method=method,
                       identifications=found)


def _points(points: Array, name: str) -> Array:
    arr = np.asarray(points, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != 3 or not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be a finite array of shape (n, 3), got shape {arr.shape}")
    return arr


def _not_recognised(exact: bool, candidates: int, method: str) -> Referencing:
    return Referencing(recognised=False, pairs=[], T_cloud_model=None, residual_rms=math.inf, matched=0,
                       ambiguous=False, alternatives=0, exact=exact, candidates=candidates, method=method)


def _identifications(model: Array, cloud: Array, tol: float, budget_s: float
                     ) -> tuple[list[Identification], bool, int, str]:
    """Accepted identifications, best score first, distinct by transform."""
    dm, dc = distance_matrix(model), distance_matrix(cloud)
    exact = True
    if len(model) * len(cloud) <= FULL_GRAPH_PAIRS:
        nodes = signature_candidates(dm, dc, tol, min_clique=3)
        method = "full graph"
    else:
        search = search_placements(model, cloud, tol, dm, dc, budget_s=0.6 * budget_s)
        exact = search.complete
        kept = sorted(search.placements, key=lambda p: (-p.size, p.rms))[:PLACEMENTS_KEPT]
        kept = [p for p in kept if p.size >= max(3, search.best - 1)]
        nodes = np.unique(np.concatenate([p.pairs for p in kept]), axis=0) if kept else np.zeros((0, 2), int)
        method = f"anchored ({search.triangles} triangles, level {search.level})"
    if len(nodes) < 3:
        return [], exact, len(nodes), method
    graph = consistency_graph(model, cloud, nodes, tol, dm, dc)
    clique_budget = 0.1 * budget_s
    if graph.size <= EXACT_CLIQUE_NODES:
        top = maximum_cliques(graph.adjacency, budget_s=clique_budget)
    else:                                            # too large to try: straight to the polynomial fallback
        top = CliqueSearch(cliques=[], exact=False)
    if top.exact and top.cliques:                    # the maximum ones and those one smaller
        near = maximal_cliques(graph.adjacency, min_size=max(3, len(top.cliques[0]) - 1), budget_s=clique_budget)
        cliques = near.cliques if near.exact else top.cliques + near.cliques
    else:
        exact = False
        method += ", dense-clique fallback"
        cliques = [dense_clique(graph.weights, graph.adjacency)] + top.cliques
    accepted = _accept(cliques, graph, model, cloud, tol)
    if not accepted:                                 # every large clique failed: look at smaller maximal ones
        rest = maximal_cliques(graph.adjacency, min_size=3, budget_s=clique_budget)
        exact = exact and rest.exact
        accepted = _accept(rest.cliques, graph, model, cloud, tol)
    return accepted, exact, len(nodes), method


def _accept(cliques: list[list[int]], graph: ConsistencyGraph, model: Array, cloud: Array,
            tol: float) -> list[Identification]:
    """Check maximal cliques and return the accepted identifications at most one point smaller than the
    largest accepted, best score first, one per transform."""
    accepted: list[Identification] = []
    tree = cKDTree(cloud)
    for clique, is_maximal in zip(cliques, _maximal(graph.adjacency, cliques), strict=True):
        if is_maximal:
            found = _verify(graph.nodes[clique], model, cloud, tree, tol)
            if found is not None:
                accepted.append(found)
    if not accepted:
        return []
    size = max(len(a.pairs) for a in accepted)
    ranked = sorted((a for a in accepted if len(a.pairs) >= size - 1), key=lambda a: -a.score)
    distinct: list[Identification] = []
    for a in ranked:
        if all(_displacement(a.T_cloud_model, b.T_cloud_model, model) > tol for b in distinct):
            distinct.append(a)
    return distinct


def _maximal(adjacency: NDArray[np.bool_], cliques: list[list[int]]) -> list[bool]:
    return [not np.any(np.all(adjacency[c], axis=0)) if c else False for c in cliques]


def _verify(pairs: NDArray[np.int64], model: Array, cloud: Array, tree: cKDTree, tol: float
            ) -> Identification | None:
    """A proper rigid fit within tolerance, not collinear, then extended by the points the fit predicts."""
    src, dst = model[pairs[:, 0]], cloud[pairs[:, 1]]
    if is_degenerate(src, tol):
        return None
    may_reject = 0.25 if len(pairs) >= 5 else 0.0
    fit = robust_rigid_transform(src, dst, threshold=tol, max_rejected=may_reject)
    if not np.all(fit.residuals[fit.inliers] <= tol):
        return None
    kept = pairs[fit.inliers]
    T = fit.T
    free_model = np.setdiff1d(np.arange(len(model)), kept[:, 0])
    if len(free_model):
        used = set(kept[:, 1].tolist())
        d, j = tree.query(apply(T, model[free_model]), k=2, distance_upper_bound=tol)
        extra = []
        for k, dd, jj in zip(free_model.tolist(), d.tolist(), j.tolist(), strict=True):
            for dist, cand in zip(dd, jj, strict=True):
                if math.isfinite(dist) and cand not in used:
                    extra.append((k, cand))
                    used.add(cand)
                    break
        if extra:
            grown = np.vstack([kept, np.array(extra, dtype=np.int64)])
            refit = robust_rigid_transform(model[grown[:, 0]], cloud[grown[:, 1]], threshold=tol,
                                           max_rejected=len(extra) / len(grown))
            inliers = refit.inliers & (refit.residuals <= tol)
            if inliers.sum() > len(kept) and np.all(refit.residuals[refit.inliers] <= tol):
                kept, fit = grown[inliers], refit
    kept, T, residuals = _best_subset(kept, model, cloud, tol, max_drop=len(kept) // 4)
    if len(kept) < 3 or is_degenerate(model[kept[:, 0]], tol):
        return None
    order = np.argsort(kept[:, 0])
    return Identification(pairs=[(int(a), int(b)) for a, b in kept[order]], T_cloud_model=T,
                          residual_rms=float(np.sqrt(np.mean(residuals ** 2))),
                          score=msac_score(residuals, tol))


def _best_subset(pairs: NDArray[np.int64], model: Array, cloud: Array, tol: float, max_drop: int
                 ) -> tuple[NDArray[np.int64], Array, Array]:
    """Drop a pair while that raises the MSAC score (the one whose removal raises it most; at most `max_drop`,
    keeping four): a pair consistent within tolerance only because the fit leans towards it costs the others
    more than it brings, and the fit leaning towards it is why its own residual need not be the largest.
    Returns the pairs, their least-squares transform and residuals."""
    def fit(subset: NDArray[np.int64]) -> tuple[Array, Array, float]:
        T = rigid_transform(model[subset[:, 0]], cloud[subset[:, 1]])
        r = np.linalg.norm(apply(T, model[subset[:, 0]]) - cloud[subset[:, 1]], axis=1)
        return T, r, msac_score(r, tol)

    T, residuals, score = fit(pairs)
    for _ in range(max_drop):
        n = len(pairs)
        if n <= 4:
            break
        src, dst = model[pairs[:, 0]], cloud[pairs[:, 1]]
        leave_out = ~np.eye(n, dtype=bool)                              # all n leave-one-out fits at once
        rot, t = rigid_transforms(np.broadcast_to(src, (n, n, 3)), np.broadcast_to(dst, (n, n, 3)), leave_out)
        r = np.linalg.norm(np.einsum("hij,nj->hni", rot, src) + t[:, None, :] - dst, axis=2)
        scores = np.where(leave_out, np.clip(1.0 - (r / tol) ** 2, 0.0, None), 0.0).sum(axis=1)
        k = int(np.argmax(scores))
        if scores[k] <= score:
            break
        pairs = np.delete(pairs, k, axis=0)
        T, residuals, score = fit(pairs)
    return pairs, T, residuals


def _displacement(T1: Array, T2: Array, model: Array) -> float:
    """Mean distance between the model's points placed by two transforms (m)."""
    return float(np.mean(np.linalg.norm(apply(T1, model) - apply(T2, model), axis=1)))


def prior_distance(T: Array, prior: Array, model: Array) -> float:
    """How far a transform is from the prior: rotation angle (rad) × RMS radius of the model + displacement
    of the model's centroid (m)."""
    centre = model.mean(axis=0)
    radius = float(np.sqrt(np.mean(np.sum((model - centre) ** 2, axis=1))))
    angle = math.radians(rotation_angle_deg(prior[:3, :3].T @ T[:3, :3]))
    shift = float(np.linalg.norm(apply(T, centre[None])[0] - apply(prior, centre[None])[0]))
    return angle * radius + shift


def _choose(equal: list[Identification], model: Array, prior: Array | None) -> tuple[Identification, bool]:
    if len(equal) == 1:
        return equal[0], False
    if prior is None:
        return equal[0], True
    prior = np.asarray(prior, dtype=float)
    ranked = sorted(equal, key=lambda e: prior_distance(e.T_cloud_model, prior, model))
    d0 = prior_distance(ranked[0].T_cloud_model, prior, model)
    d1 = prior_distance(ranked[1].T_cloud_model, prior, model)
    return ranked[0], not d0 <= CLEAR_CUT * d1
