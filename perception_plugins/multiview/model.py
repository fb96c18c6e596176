"""Multi-view object models (seed 000 §3.1, steps 1–6): per-view element sets in each view's camera frame, the
object frame built on a base segment, and the full model in the object frame with elements averaged over views.

A `ViewModel` keeps what recognition needs of one overview view (§6.1): its left image (face-side patches), its
triangulated points with their left-image pixels and descriptors, its segment lines (end points tied to their
images, face side) and corners, all in CS^view, plus `T_object_view` (the seed's H_{CS^view, CS^object}) and the
navigation pose of the camera, `T_world_view_nav`, by which views are chosen by proximity. The `ObjectModel`
adds the full model (§6.2): points, segment end points and corner points in the object frame, each the average of
its occurrences in the views (`*_ids` tie a view's elements to the full model's), and `T_database_object`, the
object frame in the database object's frame as navigation saw it (the seed's H_{CS^object, CS^SPS} when the
database frame serves as the SPS frame).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from mission.geometry import transform_points
from perception_plugins.multiview.corners import Corner, corner_points
from perception_plugins.multiview.segments import Segment

Array = NDArray[np.float64]
Image = NDArray[np.uint8]


@dataclass(eq=False)
class ViewModel:
    """One overview view's model (CS^view = its left camera frame, OpenCV axes)."""

    name: str
    K: Array
    baseline: float
    left: Image
    T_world_view_nav: Array
    T_object_view: Array
    points: Array                         # (n, 3) CS^view
    uv_left: Array                        # (n, 2)
    descriptors: NDArray[np.generic]      # (n, D)
    segments: list[Segment]
    corners: list[Corner]
    point_ids: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, np.int64))
    segment_ids: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, np.int64))
    corner_ids: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, np.int64))

    def corner_points(self, k: int) -> Array:
        """(3, 3) points of corner k in CS^view."""
        c = self.corners[k]
        a, b = self.segments[c.segments[0]], self.segments[c.segments[1]]
        return corner_points(a.points, c.ends[0], b.points, c.ends[1])

    def segment_points(self) -> Array:
        """(L, 2, 3) segment end points in CS^view."""
        return np.array([s.points for s in self.segments]).reshape(-1, 2, 3)


@dataclass(eq=False)
class ObjectModel:
    """The full multi-view model of one object."""

    object_id: str
    views: list[ViewModel]
    detector: str
    base_segment: Array                    # (2, 3) object frame: [P1, P2] of Figure 2
    points: Array = field(default_factory=lambda: np.zeros((0, 3)))        # (P, 3) object frame, averaged
    segments: Array = field(default_factory=lambda: np.zeros((0, 2, 3)))   # (L, 2, 3)
    corners: Array = field(default_factory=lambda: np.zeros((0, 3, 3)))    # (C, 3, 3)
    T_database_object: Array = field(default_factory=lambda: np.eye(4))

    def view(self, name: str) -> ViewModel:
        for v in self.views:
            if v.name == name:
                return v
        raise KeyError(name)

    def table(self) -> list[dict[str, object]]:
        """Per view: how many points, lines and corners it holds."""
        return [{"view": v.name, "points": len(v.points), "lines": len(v.segments), "corners": len(v.corners)}
                for v in self.views]


def merge_full_model(model: ObjectModel, point_links: list[tuple[int, int, int, int]], tol_m: float = 0.05) -> None:
    """Fill the full model (§3.1 step 5): points linked across views by `point_links` (view a, index, view b,
    index), segments and corners by proximity in the object frame, each element the average of its occurrences;
    sets every view's `*_ids`."""
    views = model.views
    # Points: union–find over (view, index) along the links.
    offsets = np.cumsum([0] + [len(v.points) for v in views])
    parent = np.arange(int(offsets[-1]))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = int(parent[i])
        return i

    obj = [transform_points(v.T_object_view, v.points) for v in views]
    for va, ia, vb, ib in point_links:
        a, b = find(int(offsets[va] + ia)), find(int(offsets[vb] + ib))
        if a != b and np.linalg.norm(obj[va][ia] - obj[vb][ib]) <= 2 * tol_m:
            parent[max(a, b)] = min(a, b)
    roots = np.array([find(i) for i in range(len(parent))], dtype=np.int64)
    uniq, ids = np.unique(roots, return_inverse=True)
    stacked = np.vstack(obj) if len(parent) else np.zeros((0, 3))
    sums = np.zeros((len(uniq), 3))
    np.add.at(sums, ids, stacked)
    model.points = sums / np.bincount(ids, minlength=len(uniq))[:, None]
    for k, v in enumerate(views):
        v.point_ids = ids[offsets[k]:offsets[k + 1]].astype(np.int64)
    # Segments: an end-point match within tol (either order) is the same edge.
    groups: list[list[Array]] = []
    for v in views:
        ids_v = []
        for seg in transform_points(v.T_object_view, v.segment_points().reshape(-1, 3)).reshape(-1, 2, 3):
            g = _find_segment(groups, seg, tol_m)
            if g is None:
                groups.append([seg])
                g = len(groups) - 1
            else:
                ref = groups[g][0]
                groups[g].append(seg if np.linalg.norm(seg - ref) <= np.linalg.norm(seg[::-1] - ref) else seg[::-1])
            ids_v.append(g)
        v.segment_ids = np.array(ids_v, dtype=np.int64)
    model.segments = np.array([np.mean(g, axis=0) for g in groups]).reshape(-1, 2, 3)
    cgroups: list[list[Array]] = []
    for v in views:
        ids_v = []
        for k_c in range(len(v.corners)):
            pts = transform_points(v.T_object_view, v.corner_points(k_c))
            found = next((i for i, g in enumerate(cgroups) if np.linalg.norm(g[0][0] - pts[0]) <= tol_m
                          and _same_arms(g[0], pts)), None)
            if found is None:
                cgroups.append([pts])
                found = len(cgroups) - 1
            else:
                ref = cgroups[found][0]
                cgroups[found].append(pts if np.linalg.norm(pts[1] - ref[1]) <= np.linalg.norm(pts[2] - ref[1])
                                      else pts[[0, 2, 1]])
            ids_v.append(found)
        v.corner_ids = np.array(ids_v, dtype=np.int64)
    model.corners = np.array([np.mean(g, axis=0) for g in cgroups]).reshape(-1, 3, 3)


def _find_segment(groups: list[list[Array]], seg: Array, tol: float) -> int | None:
    for k, g in enumerate(groups):
        ref = g[0]
        if max(np.linalg.norm(seg - ref, axis=1)) <= tol or max(np.linalg.norm(seg[::-1] - ref, axis=1)) <= tol:
            return k
    return None


def _same_arms(a: Array, b: Array, cos_min: float = 0.95) -> bool:
    da, db = a[1:] - a[0], b[1:] - b[0]
    da = da / np.linalg.norm(da, axis=1, keepdims=True)
    db = db / np.linalg.norm(db, axis=1, keepdims=True)
    return bool((da[0] @ db[0] > cos_min and da[1] @ db[1] > cos_min)
                or (da[0] @ db[1] > cos_min and da[1] @ db[0] > cos_min))


__all__ = ["ObjectModel", "ViewModel", "merge_full_model"]
