"""Stage 1 (seed 000 §3.2.1): a view's model points matched to a working pair's points, and H_work_view.

Both point sets are stereo-matched and triangulated already (steps 3–4 and the model's step 3.1), so matching
their left-image descriptors (steps 2, 5–8: ratio test and mutual check) gives 3D–3D putative pairs directly.
Wrong pairs are removed by structural coherence — the consistency graph of `perception_plugins.referencing` and
its maximum clique — and the least-squares transform of the rest is refined robustly (step 9). The transform is
returned as `T_view_work` (work camera → view camera coordinates: the seed's H_{CS^work, CS^view}).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from perception_plugins.referencing.clique import dense_clique, maximum_cliques
from perception_plugins.referencing.consistency import consistency_graph, distance_matrix
from perception_plugins.referencing.transform import is_degenerate, rigid_transform, robust_rigid_transform

Array = NDArray[np.float64]

MIN_POINTS = 3
MAX_PUTATIVE = 300


@dataclass(frozen=True)
class PointMatch:
    """Matched pairs (view index, work index), T_view_work and the RMS residual (m); `ok` with ≥ 3 pairs."""

    pairs: NDArray[np.int64]
    T_view_work: Array
    rms: float
    putative: int

    @property
    def ok(self) -> bool:
        return len(self.pairs) >= MIN_POINTS

    @property
    def matched(self) -> int:
        return int(len(self.pairs))


def _failed(putative: int) -> PointMatch:
    return PointMatch(np.zeros((0, 2), np.int64), np.eye(4), float("inf"), putative)


def descriptor_pairs(desc_a: NDArray[np.generic], desc_b: NDArray[np.generic], ratio: float = 0.8) -> NDArray[np.int64]:
    """Mutual nearest neighbours passing Lowe's ratio test: (k, 2) index pairs (a, b)."""
    if len(desc_a) < 2 or len(desc_b) < 2:
        return np.zeros((0, 2), np.int64)
    norm = cv2.NORM_HAMMING if desc_a.dtype == np.uint8 else cv2.NORM_L2
    matcher = cv2.BFMatcher(norm)
    forward = matcher.knnMatch(np.ascontiguousarray(desc_a), np.ascontiguousarray(desc_b), k=2)
    backward = matcher.match(np.ascontiguousarray(desc_b), np.ascontiguousarray(desc_a))
    back = {m.queryIdx: m.trainIdx for m in backward}
    out = [(m[0].queryIdx, m[0].trainIdx) for m in forward
           if len(m) == 2 and m[0].distance < ratio * m[1].distance and back.get(m[0].trainIdx) == m[0].queryIdx]
    return np.array(out, dtype=np.int64).reshape(-1, 2)


def match_points(view_points: Array, view_desc: NDArray[np.generic], work_points: Array,
                 work_desc: NDArray[np.generic], tolerance: float = 0.06, ratio: float = 0.8,
                 budget_s: float = 0.3) -> PointMatch:
    """Stage 1 between one view's model points and the working cloud (see the module docstring)."""
    pairs = descriptor_pairs(view_desc, work_desc, ratio)
    if len(pairs) < MIN_POINTS:
        return _failed(len(pairs))
    if len(pairs) > MAX_PUTATIVE:
        pairs = pairs[:MAX_PUTATIVE]
    vp, wp = np.asarray(view_points, float), np.asarray(work_points, float)
    nodes = np.column_stack([pairs[:, 0], pairs[:, 1]])
    graph = consistency_graph(vp, wp, nodes, tolerance, distance_matrix(vp), distance_matrix(wp))
    found = maximum_cliques(graph.adjacency, budget_s=budget_s)
    clique = found.cliques[0] if found.exact and found.cliques else dense_clique(graph.weights, graph.adjacency)
    if len(clique) < MIN_POINTS:
        return _failed(len(pairs))
    kept = nodes[np.asarray(clique)]
    src, dst = wp[kept[:, 1]], vp[kept[:, 0]]
    if is_degenerate(dst, tolerance):
        return _failed(len(pairs))
    fit = robust_rigid_transform(src, dst, threshold=tolerance, max_rejected=0.3)
    kept = kept[fit.inliers]
    if len(kept) < MIN_POINTS:
        return _failed(len(pairs))
    T = weighted_fit(wp[kept[:, 1]], vp[kept[:, 0]], wp[kept[:, 1], 2], vp[kept[:, 0], 2])
    return PointMatch(kept[np.argsort(kept[:, 0])], T, fit.rms, len(pairs))


def depth_weights(z_a: Array, z_b: Array) -> Array:
    """Least-squares weights of pairs of stereo points at depths z_a, z_b: 1 / (σ_a² + σ_b²) with σ ∝ Z²
    (σ_Z = Z²·σ_d / (f·B); the common factor cancels)."""
    return np.asarray(1.0 / (np.asarray(z_a, float) ** 4 + np.asarray(z_b, float) ** 4))


def weighted_fit(src: Array, dst: Array, z_src: Array, z_dst: Array) -> Array:
    """The rigid transform src → dst weighted by the pairs' stereo depth uncertainty: far seabed points, whose
    depth σ grows with Z², count less than the object's nearer faces."""
    return rigid_transform(src, dst, depth_weights(z_src, z_dst))


__all__ = ["MIN_POINTS", "PointMatch", "depth_weights", "descriptor_pairs", "match_points", "weighted_fit"]
