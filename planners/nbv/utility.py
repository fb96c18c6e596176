"""The next-best-view utility of seed 002 §2.2.2:

    u_i = (d_i·w_d + f_i / max(f)·w_f + ct_i / max(ct)·w_ct) · ol_i

* d_i ∈ (0, 1], the influence of the view's distance from the vehicle: exp(−dist_i / R) with R the scanner's
  range (1 at the vehicle, 1/e one scanner range away; an absolute scale, so that how far the other candidates
  happen to lie does not change how much a metre costs);
* f_i: unknown voxels the view would reveal (`visibility.unknown`);
* ct_i: known structure the view would follow: occupied voxels on the contour of the known structure that the
  view sees (`visibility.contour`);
* ol_i: the overlap of the explored areas. The seed names the term without a formula; here it is the overlap a
  new scan needs with the structure already mapped (to be registered to it and to continue it): the share of
  the view's rays that end on known structure, relative to `min_overlap`, capped at 1 —
  ol_i = min(1, hit_fraction_i / min_overlap). While no structure is known at all, ol = 1 for every view.
* the weights are the behaviours' shares and sum to one (the seed): w_f ≫ w_ct explores frontiers, w_ct ≫ w_f
  follows the contours of what has been seen.

>>> terms = utility_terms(np.array([0.0, 12.0]), np.array([4, 0]), np.array([0, 8]), np.array([0.5, 0.05]),
...                       Weights(0.2, 0.4, 0.4), min_overlap=0.1, distance_scale=12.0)
>>> terms.d.round(3).tolist(), terms.ol.tolist(), terms.u.round(3).tolist()
([1.0, 0.368], [1.0, 0.5], [0.6, 0.237])
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from planners.nbv.grid import StateGrid
from planners.nbv.views import Scanner, Views
from planners.nbv.visibility import visibility

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Weights:
    """w_d, w_f, w_ct of the utility; non-negative, summing to one (the mission's `explore.weights`)."""

    distance: float = 0.3
    frontier: float = 0.5
    contour: float = 0.2

    def __post_init__(self) -> None:
        values = (self.distance, self.frontier, self.contour)
        if min(values) < 0:
            raise ValueError(f"weights must be non-negative, got {values}")
        if not math.isclose(sum(values), 1.0, abs_tol=1e-6):
            raise ValueError(f"weights must sum to 1 (seed 002 §2.2.2), got {values} (sum {sum(values):g})")


FRONTIER = Weights(distance=0.1, frontier=0.85, contour=0.05)
"""w_f ≫ w_ct: classic frontier exploration."""
CONTOUR = Weights(distance=0.1, frontier=0.05, contour=0.85)
"""w_ct ≫ w_f: contour following."""


@dataclass(frozen=True)
class ViewTerms:
    """Per-view terms of the utility and the utility itself."""

    d: Array
    f: NDArray[np.int64]
    ct: NDArray[np.int64]
    ol: Array
    u: Array
    hit_fraction: Array
    occupied: NDArray[np.int64]


def overlap_term(hit_fraction: ArrayLike, min_overlap: float) -> Array:
    """ol_i = min(1, hit_fraction_i / min_overlap); all ones while no view sees known structure."""
    h = np.asarray(hit_fraction, dtype=float)
    if not len(h) or h.max() <= 0:
        return np.ones(len(h))
    return np.asarray(np.minimum(1.0, h / min_overlap)) if min_overlap > 0 else np.ones(len(h))


def utility_terms(dist: ArrayLike, f: ArrayLike, ct: ArrayLike, hit_fraction: ArrayLike, weights: Weights,
                  min_overlap: float = 0.1, occupied: ArrayLike | None = None,
                  distance_scale: float = 12.0) -> ViewTerms:
    """The utility from raw per-view quantities (`dist` metres from the vehicle)."""
    dd = np.asarray(dist, dtype=float)
    d = np.exp(-dd / distance_scale)
    fi = np.asarray(f, dtype=np.int64)
    ci = np.asarray(ct, dtype=np.int64)
    f_norm = fi / fi.max() if len(fi) and fi.max() > 0 else np.zeros(len(fi))
    c_norm = ci / ci.max() if len(ci) and ci.max() > 0 else np.zeros(len(ci))
    ol = overlap_term(hit_fraction, min_overlap)
    u = (d * weights.distance + f_norm * weights.frontier + c_norm * weights.contour) * ol
    occ = np.zeros(len(fi), dtype=np.int64) if occupied is None else np.asarray(occupied, dtype=np.int64)
    return ViewTerms(d, fi, ci, ol, u, np.asarray(hit_fraction, dtype=float), occ)


def view_utility(grid: StateGrid, views: Views, current: ArrayLike, scanner: Scanner, weights: Weights, *,
                 min_overlap: float = 0.1, step: float | None = None, contour: ArrayLike | None = None) -> ViewTerms:
    """The terms d, f, ct, ol and u of every view, from the vehicle's position `current` (3,)."""
    vis = visibility(grid, views, scanner, step=step, contour=contour)
    dist = np.linalg.norm(views.positions - np.asarray(current, dtype=float).reshape(3), axis=1)
    return utility_terms(dist, vis.unknown, vis.contour, vis.hit_fraction, weights, min_overlap, vis.occupied,
                         distance_scale=scanner.max_range)


def next_best_view(grid: StateGrid, views: Views, current: ArrayLike, scanner: Scanner, weights: Weights, *,
                   min_overlap: float = 0.1, step: float | None = None,
                   contour: ArrayLike | None = None) -> tuple[int, ViewTerms]:
    """Index of the view with the highest utility (−1 when there are no views), and all views' terms."""
    terms = view_utility(grid, views, current, scanner, weights, min_overlap=min_overlap, step=step,
                         contour=contour)
    return (int(np.argmax(terms.u)) if len(views) else -1), terms
