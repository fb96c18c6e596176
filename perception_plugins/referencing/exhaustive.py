"""The paper's identification search (seed 002 §3.2), kept as a test oracle for small sets.

Subsets S_k of the model and S_l of the cloud of equal size n are compared, from n = min(N, M) down to 3; the
first pair whose distance multisets D_k and D_l agree (within `tolerance`, element by element once sorted) and
whose points can be put in correspondence (task 2: every point's distances agree with its partner's) is the
identification. Σₙ C(N, n)·C(M, n) comparisons: exponential, usable only for a handful of points. Like the
paper, it looks at distances only, so it cannot tell a set from its mirror image.

>>> import numpy as np
>>> model = np.array([[0.0, 0, 0], [4, 0, 0], [0, 3, 0], [0, 0, 2]])
>>> cloud = np.vstack([[9.0, 9, 9], model[[2, 0, 3, 1]] + 1.0])
>>> exhaustive_identify(model, cloud, tolerance=0.01)
[(0, 2), (1, 4), (2, 1), (3, 3)]
"""

from __future__ import annotations

from itertools import combinations

import numpy as np
from numpy.typing import NDArray

from perception_plugins.referencing.consistency import distance_matrix

Array = NDArray[np.float64]


def _sorted_distances(d: Array, subset: tuple[int, ...]) -> Array:
    idx = np.array(subset)
    return np.sort(d[np.ix_(idx, idx)][np.triu_indices(len(idx), 1)])


def _correspond(dm: Array, dc: Array, model_subset: tuple[int, ...], cloud_subset: tuple[int, ...],
                tolerance: float) -> list[tuple[int, int]] | None:
    """Task 2: a one-to-one assignment under which every pair of distances agrees (backtracking)."""
    assignment: list[int] = []

    def place(p: int, used: int) -> bool:
        if p == len(model_subset):
            return True
        i = model_subset[p]
        for q, j in enumerate(cloud_subset):
            if used >> q & 1:
                continue
            if all(abs(dm[i, model_subset[r]] - dc[j, cloud_subset[assignment[r]]]) <= tolerance
                   for r in range(p)):
                assignment.append(q)
                if place(p + 1, used | 1 << q):
                    return True
                assignment.pop()
        return False

    if not place(0, 0):
        return None
    return [(model_subset[p], cloud_subset[q]) for p, q in enumerate(assignment)]


def exhaustive_identify(model_points: Array, cloud_points: Array, tolerance: float) -> list[tuple[int, int]]:
    """The seed's search: pairs (model index, cloud index) of the first coherent subsets, largest n first."""
    dm, dc = distance_matrix(model_points), distance_matrix(cloud_points)
    n_model, n_cloud = len(dm), len(dc)
    for n in range(min(n_model, n_cloud), 2, -1):
        cloud_subsets = list(combinations(range(n_cloud), n))
        cloud_sorted = np.array([_sorted_distances(dc, s) for s in cloud_subsets])
        for model_subset in combinations(range(n_model), n):
            d_model = _sorted_distances(dm, model_subset)
            # the multiset test D_l = D_k against every cloud subset at once, in the paper's order
            for q in np.nonzero(np.all(np.abs(cloud_sorted - d_model) <= tolerance, axis=1))[0].tolist():
                pairs = _correspond(dm, dc, model_subset, cloud_subsets[q], tolerance)
                if pairs is not None:
                    return sorted(pairs)
    return []
