"""Placements of the model in the cloud (seed 002 §3.2–3.3): from the congruent copies of an anchor triangle to
refined rigid placements with their pairs.

A copy fixes a proper transform; copies are ranked by how many model points land on cloud points (a dilated
occupancy grid for thousands of copies; for the best few dozen, one batched gather-and-refit step and exact
distances), the best are refined by gathering and refitting with a shrinking radius, and the final best are
given a local optimisation that lets a placement leave a wrong basin (LO-RANSAC). Scores are MSAC scores.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from itertools import combinations

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from perception_plugins.referencing.transform import (
    apply,
    msac_score,
    rigid_transform,
    rigid_transforms,
    robust_rigid_transform,
    triangle_transforms,
)

Array = NDArray[np.float64]
Index = NDArray[np.int64]

REFINED_PER_TRIANGLE = 3          # copies of an anchor triangle refined into placements
# Ranking stages, (sparse, dense): a dense cloud (more than DENSE_COPIES copies of a triangle) makes chance
# copies hit as often as the true one on a few points, so it needs more points and longer shortlists.
DENSE_COPIES = 5000
FIRST_STAGE = (6, 10)             # model points that score every congruent copy (on the grid),
SECOND_STAGE = (256, 512)         # copies that the rest of the scored points then score (on the grid),
THIRD_STAGE = (48, 64)            # copies then refitted once and scored by exact distances of every model point
LO_TRIPLES = 256                  # triples of candidate pairs tried by the local optimisation


@dataclass(frozen=True)
class Placement:
    """A rigid placement of the model in the cloud: its pairs (k, 2), transform T_cloud_model, RMS residual."""

    pairs: Index
    T: Array
    rms: float
    score: float = 0.0                # MSAC score of the pairs' residuals

    @property
    def size(self) -> int:
        return int(len(self.pairs))


class OccupancyGrid:
    """A dilated occupancy grid of the cloud: constant-time "is a cloud point near here?" for many points."""

    def __init__(self, cloud: Array, cell: float, max_cells: int = 4_000_000):
        lo, hi = cloud.min(axis=0) - 2.0 * cell, cloud.max(axis=0) + 2.0 * cell
        cell = max(cell, float(np.prod(hi - lo) / max_cells) ** (1.0 / 3.0))
        self.lo, self.cell = lo, cell
        self.shape = np.ceil((hi - lo) / cell).astype(np.int64) + 1
        occ = np.zeros(tuple(self.shape), dtype=bool)
        ijk = np.floor((cloud - lo) / cell).astype(np.int64)
        occ[ijk[:, 0], ijk[:, 1], ijk[:, 2]] = True
        for axis in range(3):                          # dilation by the 3×3×3 cube, one axis at a time
            grown = occ.copy()
            lo_side = [slice(None)] * 3
            hi_side = [slice(None)] * 3
            lo_side[axis], hi_side[axis] = slice(1, None), slice(None, -1)
            grown[tuple(lo_side)] |= occ[tuple(hi_side)]
            grown[tuple(hi_side)] |= occ[tuple(lo_side)]
            occ = grown
        self.flat = occ.ravel()

    def near(self, points: Array) -> NDArray[np.bool_]:
        ijk = ((points - self.lo) * (1.0 / self.cell)).astype(np.int64)     # truncation: floor inside the box
        inside = np.all((ijk >= 0) & (ijk < self.shape), axis=-1)
        flat = (ijk[..., 0] * self.shape[1] + ijk[..., 1]) * self.shape[2] + ijk[..., 2]
        return np.asarray(inside & self.flat[np.where(inside, flat, 0)], dtype=bool)


def _gather(model: Array, tree: cKDTree, T: Array, radius: float) -> Index:
    """Pairs (model k, cloud j) of model points that T places within `radius` of a cloud point, one-to-one
    (a cloud point goes to the model point closest to it)."""
    d, j = tree.query(apply(T, model), distance_upper_bound=radius)
    k = np.nonzero(np.isfinite(d))[0]
    k = k[np.argsort(d[k], kind="stable")]
    _, first = np.unique(j[k], return_index=True)
    k = np.sort(k[first])
    return np.stack([k, j[k]], axis=1).astype(np.int64)


def refine(model: Array, cloud: Array, tree: cKDTree, T: Array, tolerance: float, needed: int
           ) -> Placement | None:
    """Gather the pairs a coarse placement predicts and refit, with a radius shrinking from 3·tolerance to the
    tolerance, until the pairs no longer change; then fit robustly and keep the pairs within tolerance.
    Gives up as soon as fewer than `needed` pairs are gathered."""
    radius, previous = 3.0 * tolerance, b""
    for _ in range(12):
        pairs = _gather(model, tree, T, radius)
        if len(pairs) < max(3, needed):
            return None
        T = rigid_transform(model[pairs[:, 0]], cloud[pairs[:, 1]])
        key = pairs.tobytes()
        if radius == tolerance and key == previous:
            break
        previous, radius = key, max(tolerance, 0.6 * radius)
    fit = robust_rigid_transform(model[pairs[:, 0]], cloud[pairs[:, 1]], threshold=tolerance)
    inliers = fit.inliers & (fit.residuals <= tolerance)
    pairs = pairs[inliers]
    if len(pairs) < max(3, needed):
        return None
    return Placement(pairs=pairs, T=fit.T, rms=fit.rms, score=msac_score(fit.residuals[inliers], tolerance))


def local_optimise(model: Array, cloud: Array, tree: cKDTree, placement: Placement, tolerance: float
                   ) -> Placement | None:
    """Escape a wrong basin of the refinement (a placement that leaned onto a nearby outlier): the two nearest
    cloud points within 3·tolerance of each placed model point are candidate pairs, every triple of them (at
    most LO_TRIPLES) gives a proper transform, and the one placing the model best (MSAC score of the model points'
    distances to the cloud) is refined again (local optimisation as in LO-RANSAC, Chum et al. 2003).
    Returns a placement larger than the given one, or as large with a better score; otherwise None."""
    d, j = tree.query(apply(placement.T, model), k=2, distance_upper_bound=3.0 * tolerance)
    k_idx, slot = np.nonzero(np.isfinite(d))
    cands = np.stack([k_idx, j[k_idx, slot]], axis=1)
    if len(cands) <= 3:
        return None
    if math.comb(len(cands), 3) <= LO_TRIPLES:
        triples = np.array(list(combinations(range(len(cands)), 3)), dtype=np.int64)
    else:
        triples = np.random.default_rng(0).integers(0, len(cands), (3 * LO_TRIPLES, 3))
    m_of, c_of = cands[triples, 0], cands[triples, 1]
    distinct = ((m_of[:, 0] != m_of[:, 1]) & (m_of[:, 0] != m_of[:, 2]) & (m_of[:, 1] != m_of[:, 2])
                & (c_of[:, 0] != c_of[:, 1]) & (c_of[:, 0] != c_of[:, 2]) & (c_of[:, 1] != c_of[:, 2]))
    triples = triples[distinct][:LO_TRIPLES]
    if len(triples) == 0:
        return None
    rot, t = rigid_transforms(model[cands[triples, 0]], cloud[cands[triples, 1]])
    dist, _ = tree.query(_moved(rot, t, model).reshape(-1, 3), distance_upper_bound=tolerance)
    dist = dist.reshape(len(triples), len(model))
    msac = np.where(np.isfinite(dist), 1.0 - (np.minimum(dist, tolerance) / tolerance) ** 2, 0.0).sum(axis=1)
    h = int(np.argmax(msac))
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = rot[h], t[h]
    if _displacement(T, placement.T, model) <= 0.25 * tolerance:
        return None                                   # the same basin
    better = refine(model, cloud, tree, T, tolerance, needed=placement.size)
    if better is None or (better.size, better.score) <= (placement.size, placement.score):
        return None
    return better


def placements_of(tri: tuple[int, int, int], copies: Index, model: Array, cloud: Array, tolerance: float,
                  scored: Index, grid: OccupancyGrid, tree: cKDTree, needed: int, known: list[Array]
                  ) -> list[Placement]:
    """The best-supported placements that the congruent copies (h, 3) of the model triangle `tri` give.

    Copies are ranked in three stages, each on fewer of them: grid hits of a few spread model points (of
    `scored`), grid hits of the rest of `scored`, then, after one refit on the pairs within 2·tolerance (a
    triangle's transform is rough far from it), the MSAC score of every model point's distance to the cloud.
    The best few are refined, unless they cannot reach `needed` pairs or a placement in `known` (transforms)
    already puts the model there.
    """
    if len(copies) == 0:
        return []
    rot, t = triangle_transforms(model[list(tri)], cloud[copies])
    others = np.array([k for k in scored.tolist() if k not in tri], dtype=np.int64)
    rank = np.arange(len(copies))
    if len(others):
        dense = int(len(copies) > DENSE_COPIES)
        first = others[:FIRST_STAGE[dense]]
        score = grid.near(_moved(rot, t, model[first])).sum(axis=1)
        rank = np.argsort(-score, kind="stable")[:SECOND_STAGE[dense]]
        if len(others) > len(first):
            score = score[rank] + grid.near(_moved(rot[rank], t[rank], model[others[len(first):]])).sum(axis=1)
            rank = rank[np.argsort(-score, kind="stable")[:THIRD_STAGE[dense]]]
    # one gather-and-refit step for the best copies, all at once: their MSAC scores at the tolerance then
    # tell a placement that fits at the noise level from chance ones far better than the rough copy does
    d, j = tree.query(_moved(rot[rank], t[rank], model).reshape(-1, 3), distance_upper_bound=2.0 * tolerance)
    near = np.isfinite(d).reshape(len(rank), len(model))
    j = np.where(near, j.reshape(len(rank), len(model)), 0)
    rot2, t2 = rigid_transforms(np.broadcast_to(model, (len(rank),) + model.shape), cloud[j], near)
    usable = near.sum(axis=1) >= 3
    rot = rot.copy()
    rot[rank[usable]], t = rot2[usable], t.copy()
    t[rank[usable]] = t2[usable]
    d, _ = tree.query(_moved(rot[rank], t[rank], model).reshape(-1, 3), distance_upper_bound=tolerance)
    d = d.reshape(len(rank), len(model))
    count = np.isfinite(d).sum(axis=1)
    msac = np.where(np.isfinite(d), 1.0 - (np.minimum(d, tolerance) / tolerance) ** 2, 0.0).sum(axis=1)
    order = np.argsort(-msac, kind="stable")
    top = rank[order][:REFINED_PER_TRIANGLE]
    reach = count[order][:REFINED_PER_TRIANGLE]
    # the best copy, and the next ones only if they reach about as far (a symmetric set's other placements)
    top = top[(reach >= needed) & (reach >= min(4, reach[0])) & (reach >= reach[0] - 1)]
    if reach[0] <= 3:
        top = top[:2]                 # the triangle alone: two copies tell a unique one from a chance one
    known = list(known)
    found = []
    for h in top.tolist():
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = rot[h], t[h]
        if any(_displacement(T, K, model) <= 3.0 * tolerance for K in known):
            continue
        placement = refine(model, cloud, tree, T, tolerance, needed=needed)
        if placement is not None:
            found.append(placement)
            known.append(placement.T)
    return found


def _moved(rot: Array, t: Array, points: Array) -> Array:
    """Points (k, 3) under each of h transforms: (h, k, 3), by broadcasting (BLAS is slow on these shapes)."""
    p = points[None, :, :, None]
    return (rot[:, None, :, 0] * p[:, :, 0] + rot[:, None, :, 1] * p[:, :, 1] + rot[:, None, :, 2] * p[:, :, 2]
            + t[:, None, :])


def _displacement(T1: Array, T2: Array, points: Array) -> float:
    """Mean distance between the points placed by two transforms."""
    return float(np.mean(np.linalg.norm(apply(T1, points) - apply(T2, points), axis=1)))
