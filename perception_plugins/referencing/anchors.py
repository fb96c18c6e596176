"""Candidate pruning by anchor triangles: the seed's descent over subset sizes (002 §3.2, n = min(N, M) down to
3), made polynomial.

Every identification of n ≥ 3 points contains triangles of model points, and each appears in the cloud as a
congruent triangle (a 3-clique of the consistency graph). A congruent copy fixes a proper rigid placement of the
whole model, which `placements` scores (the 4-cliques that extend the triangle with the right handedness) and
refines. The pairs of the best placements become the candidates of the consistency graph.

Which triangles must be tried? For level n the model points are split into groups so that every set of n
model points holds three points of one group (pigeonhole: a set avoiding that has at most two points per
group). Trying those triangles meets every identification of ≥ n points (`triangle_plan`). The search descends
n = N, N − 1, … and stops at the first level n with a placement of ≥ n points, so that the largest
placements and every tie with them are met; below SLACK_BELOW points it goes one level further, because in a
dense cloud a chance set can be one point larger than a small true one and the MSAC score must choose.
Thin anchor triangles come last within their group's choice: their transforms are too rough far from them.

What is exact and what is not: the plan meets every identification (given that its three distances are
within tolerance, as in any clique); the ranking of a triangle's copies and the refinement that follows are
heuristics (with a local optimisation of the best placements to repair a refinement that went astray), checked
against the full graph and the exhaustive search in the tests. Cost: O(M²) per triangle for its congruent
copies (their number grows like M³·(tolerance / extent)³), O(h·N) to score h copies; O(N) triangles at the top
levels and O(N³/n²) at level n, against the seed's Σₙ C(N, n)·C(M, n) subset pairs.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from itertools import combinations, permutations

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from perception_plugins.referencing.placements import OccupancyGrid, Placement, local_optimise, placements_of

Array = NDArray[np.float64]
Index = NDArray[np.int64]

SCORED_POINTS = 16                # model points that score copies (the first in farthest-point order)
POLISHED = 4                      # best placements given a local optimisation at the end
SLACK_BELOW = 10                  # below this many points, placements one point smaller are sought too
THIN = 1e200                      # cost factor that puts thin triangles after all others


@dataclass
class AnchorSearch:
    """The outcome: distinct placements found, the largest size, the level down to which the search is exact
    (every identification of at least that many points was met), triangles tried, and whether it completed."""

    placements: list[Placement] = field(default_factory=list)
    best: int = 0
    level: int = 0
    triangles: int = 0
    complete: bool = False


def farthest_point_order(points: Array) -> Index:
    """Points ordered so that each is the farthest from those before it (spread-out groups and triangles)."""
    pts = np.asarray(points, dtype=float)
    start = int(np.argmax(np.linalg.norm(pts - pts.mean(axis=0), axis=1)))
    order = [start]
    dist = np.linalg.norm(pts - pts[start], axis=1)
    for _ in range(len(pts) - 1):
        nxt = int(np.argmax(dist))
        order.append(nxt)
        dist = np.minimum(dist, np.linalg.norm(pts - pts[nxt], axis=1))
    return np.asarray(order, dtype=np.int64)


def triangle_plan(order: Index, level: int,
                  cost: Callable[[tuple[int, int, int]], float] | None = None) -> list[tuple[int, int, int]]:
    """Triangles that meet every set of `level` model points (see the module docstring).

    The points, in farthest-point order, are dealt round-robin into groups of four. A set avoiding every
    triangle of a group holds at most two of its points (a triple taken from a group already caps it at two of
    those three), so with f full groups and t further groups contributing their first triple, such a set has at
    most N − 2f − t points; level n needs 2f + t ≥ N − n + 1. The plans are nested (a lower level only adds
    triangles), so the descent repeats no work. The triple a group contributes is its cheapest by `cost` (any
    triple of the group serves the argument). Below that (n ≤ ~N/2) the points are dealt into
    ⌊(n − 1)/2⌋ groups and every triangle inside each group is used.

    >>> triangle_plan(np.arange(12), 12)           # all points: any one triangle will do
    [(0, 3, 6)]
    >>> len(triangle_plan(np.arange(12), 8))       # reduction 5 from 3 groups: 2 full (4 each) and 1 triple
    9
    """
    n = len(order)
    reduction = n - level + 1
    groups = max(1, n // 4)
    if n >= 8 and reduction <= 2 * groups:
        dealt = [order[g::groups][:4] for g in range(groups)]
        full = max(0, reduction - groups)
        triples = reduction - 2 * full
        chosen = [list(combinations(g, 3)) for g in dealt[:full]]
        for g in dealt[full:full + triples]:
            options = list(combinations(g, 3))
            chosen.append([min(options, key=cost) if cost is not None else options[0]])
    else:
        count = max(1, (level - 1) // 2)
        chosen = [list(combinations(order[g::count], 3)) for g in range(count)]
    plan: list[tuple[int, int, int]] = []
    for k in range(max((len(c) for c in chosen), default=0)):   # interleave: good triangles early
        plan.extend(c[k] for c in chosen if k < len(c))
    return [(int(a), int(b), int(c)) for a, b, c in (sorted(t) for t in plan)]


def congruent_triangles(tri: tuple[int, int, int], model_distances: Array, cloud_distances: Array,
                        tolerance: float, frequency: Callable[[float], float] | None = None) -> Index:
    """Every cloud triangle (h, 3) whose sides match the model triangle's within `tolerance`, columns in the
    order of `tri`: the 3-cliques of the consistency graph on the model points `tri`.

    Pairs matching one side are expanded by the points matching a second side from the same vertex, then the
    third side is checked; with `frequency` (how often a distance occurs in the cloud) the two rarest sides
    are expanded, which does the least work.
    """
    perm: tuple[int, ...] = (0, 1, 2)
    if frequency is not None:
        perm = min(permutations(range(3)), key=lambda p: frequency(model_distances[tri[p[0]], tri[p[1]]])
                   * frequency(model_distances[tri[p[0]], tri[p[2]]]))
    a, b, c = (tri[i] for i in perm)
    m = len(cloud_distances)

    def matching(d: float) -> Index:
        return np.flatnonzero((cloud_distances >= d - tolerance) & (cloud_distances <= d + tolerance))

    first_end, second_end = np.divmod(matching(model_distances[a, b]), m)
    rows, cols = np.divmod(matching(model_distances[a, c]), m)
    starts = np.searchsorted(rows, np.arange(m + 1))
    counts = starts[first_end + 1] - starts[first_end]
    total = int(counts.sum())
    if total == 0:
        return np.zeros((0, 3), dtype=np.int64)
    first = np.repeat(starts[first_end] - np.concatenate([[0], np.cumsum(counts)[:-1]]), counts)
    n = cols[first + np.arange(total)]
    jj, ll = np.repeat(first_end, counts), np.repeat(second_end, counts)
    side = cloud_distances.ravel()[ll * m + n]
    ok = (np.abs(side - model_distances[b, c]) <= tolerance) & (n != jj) & (n != ll)
    found = np.stack([jj[ok], ll[ok], n[ok]], axis=1).astype(np.int64)
    copies = np.empty_like(found)
    copies[:, list(perm)] = found
    return copies


def search_placements(model: Array, cloud: Array, tolerance: float, model_distances: Array,
                      cloud_distances: Array, budget_s: float = 2.0, slack: int = 1) -> AnchorSearch:
    """Descend the levels n = min(N, M) … 3, trying each level's anchor triangles, until every placement with
    at least `best` points has been met, or (best − slack) points while best < SLACK_BELOW: in a dense cloud a
    chance set can be one point larger than a small true one, and the MSAC score must then choose. Finally the
    best placements are polished (`placements.local_optimise`)."""
    t0 = time.thread_time()
    n_model = len(model)
    order = farthest_point_order(model)
    scored = order[: min(SCORED_POINTS, n_model)]
    grid = OccupancyGrid(cloud, cell=tolerance)
    tree = cKDTree(cloud)
    out = AnchorSearch()
    seen: set[bytes] = set()
    tried: set[tuple[int, int, int]] = set()

    def add(placement: Placement) -> None:
        key = placement.pairs.tobytes()
        if key not in seen:
            seen.add(key)
            out.placements.append(placement)
            out.best = max(out.best, placement.size)

    level = min(n_model, len(cloud))
    histogram = _DistanceHistogram(cloud_distances, tolerance)

    radius = float(np.sqrt(np.mean(np.sum((model - model.mean(axis=0)) ** 2, axis=1))))

    costs: dict[tuple[int, int, int], float] = {}

    def cost(tri: tuple[int, int, int]) -> float:
        """Expected congruent copies (up to a constant), for triangles whose smallest height is at least a
        third of the model's RMS radius; thinner ones come after all of those, by height: a thin triangle's
        transform is too rough far from it for the refinement to find its way."""
        if tri not in costs:
            a, b, c = tri
            ab, ac, bc = float(model_distances[a, b]), float(model_distances[a, c]), float(model_distances[b, c])
            s = (ab + ac + bc) / 2.0                                   # Heron: twice the area over the longest side
            height = 2.0 * math.sqrt(max(s * (s - ab) * (s - ac) * (s - bc), 0.0)) / max(ab, ac, bc, 1e-12)
            if height < radius / 3.0:
                costs[tri] = THIN * radius / max(height, 1e-12)
            else:
                costs[tri] = histogram.frequency(ab) * histogram.frequency(ac) * histogram.frequency(bc)
        return costs[tri]

    while level >= 3:
        for tri in triangle_plan(order, level, cost):
            if tri in tried:
                continue
            tried.add(tri)
            out.triangles += 1
            copies = congruent_triangles(tri, model_distances, cloud_distances, tolerance, histogram.frequency)
            known = [p.T for p in out.placements if p.size >= out.best - slack]
            for placement in placements_of(tri, copies, model, cloud, tolerance, scored, grid, tree,
                                           needed=out.best - slack, known=known):
                add(placement)
            if time.thread_time() - t0 > budget_s:
                break
        else:
            if out.best - (slack if out.best < SLACK_BELOW else 0) >= level or level == 3:
                out.level, out.complete = level, True
                break
            level -= 1
            continue
        out.level = level + 1                        # the budget ran out inside this level
        break
    best_first = sorted(out.placements, key=lambda p: (-p.size, p.rms))
    for placement in best_first[:POLISHED]:
        if placement.size >= out.best - slack:
            polished = local_optimise(model, cloud, tree, placement, tolerance)
            if polished is not None:
                add(polished)
    return out


class _DistanceHistogram:
    """How often a distance (± tolerance) occurs in the cloud: bins of tolerance / 2 over the ordered pairs of
    a sample of rows, scaled to all of them."""

    def __init__(self, cloud_distances: Array, tolerance: float, rows: int = 128):
        self.step, self.tolerance = tolerance / 2.0, tolerance
        m = len(cloud_distances)
        sample = cloud_distances[:: max(1, m // rows)]                # an estimate is all the ordering needs
        bins = np.minimum((sample.ravel() / self.step).astype(np.int64), 1_000_000)
        self.cumulative = np.concatenate([[0], np.cumsum(np.bincount(bins))]) * (m / len(sample))

    def frequency(self, d: float) -> float:
        top = len(self.cumulative) - 1
        lo = min(top, max(0, int((d - self.tolerance) / self.step)))
        hi = min(top, int((d + self.tolerance) / self.step) + 1)
        return float(self.cumulative[hi] - self.cumulative[lo]) + 1.0


