"""Model formation from overview views (seed 000 §3.1, steps 3–6): per view, points (stereo matched and
triangulated), segment lines and corners, the operator's edits; the object frame on the base segment (Figure 2)
with z along the world z from the navigation attitude; each view's T_object_view; the full model averaged.

Views that do not see the base segment are placed by their transform to an already placed view, measured by
matching their points (stage 1 between the two views: the seed uses its visual navigation method there); when
that fails, the navigation poses give it. The base segment is the operator's, or else the longest near-horizontal
segment of the first view.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from mission.geometry import invert, transform_points
from perception_plugins.multiview.corners import find_corners
from perception_plugins.multiview.edits import Edits, ViewEdits
from perception_plugins.multiview.errors import MultiviewError
from perception_plugins.multiview.model import ObjectModel, ViewModel, merge_full_model
from perception_plugins.multiview.object_frame import object_frame
from perception_plugins.multiview.patches import scan_row
from perception_plugins.multiview.points import match_points
from perception_plugins.multiview.segments import Segment, match_end_points, segment_from_disparities, stereo_segments
from perception_plugins.stereo.camera import RectifiedStereo
from perception_plugins.stereo.features import Detector
from perception_plugins.stereo.pipeline import stereo_cloud
from perception_plugins.stereo.triangulation import triangulate

Array = NDArray[np.float64]
Image = NDArray[np.uint8]

MAX_BASE_TILT_DEG = 20.0


@dataclass(frozen=True, eq=False)
class ViewInput:
    """An overview stereo pair (rectified, grey) with the navigation estimate of its left camera pose."""

    name: str
    left: Image
    right: Image
    K: Array
    baseline: float
    T_world_cam_nav: Array


@dataclass(frozen=True)
class FormationSettings:
    detector: Detector = "sift"
    max_features: int = 1500
    max_range: float = 10.0
    min_length_px: float = 60.0
    tolerance: float = 0.06          # m: stage-1 consistency between views
    merge_tol: float = 0.05          # m: elements this close in the object frame are one element


def _geometry(view: ViewInput) -> RectifiedStereo:
    h, w = view.left.shape[:2]
    return RectifiedStereo.from_K(view.K, view.baseline, (w, h))


def describe_at(image: Image, uv: Array, detector: Detector) -> NDArray[np.generic]:
    """Descriptors of the given pixels (for points an operator adds), in the detector's descriptor space."""
    kps = [cv2.KeyPoint(float(u), float(v), 16.0 if detector == "sift" else 31.0, 0.0) for u, v in uv]
    extractor = cv2.SIFT_create() if detector == "sift" else cv2.ORB_create(edgeThreshold=16, patchSize=31)  # type: ignore[attr-defined]
    kept, desc = extractor.compute(image, kps)
    if desc is None or len(kept) != len(kps):
        raise MultiviewError("a picked point lies too close to the image border to be described")
    return np.asarray(desc)


def view_elements(view: ViewInput, settings: FormationSettings, edits: ViewEdits
                  ) -> tuple[Array, Array, NDArray[np.generic], list[Segment]]:
    """Points (CS^view), their left pixels and descriptors, and segments of one view, with the edits applied."""
    geo = _geometry(view)
    cloud = stereo_cloud(view.left, view.right, geo, settings.detector, settings.max_features,
                         max_range=settings.max_range)
    points, uv, desc = cloud.points_cam, cloud.uv_left, cloud.descriptors
    keep = np.ones(len(points), dtype=bool)
    for at, radius in edits.remove_points:
        keep &= np.linalg.norm(uv - at, axis=1) > radius
    points, uv, desc = points[keep], uv[keep], desc[keep]
    if edits.add_points:
        d_min, d_max = geo.disparity_range(0.5, settings.max_range)
        added = np.array(edits.add_points)
        found = []
        for p in added:
            g = np.stack(np.meshgrid(np.arange(-6.0, 7), np.arange(-6.0, 7)), axis=-1).reshape(-1, 2) + p
            peak = scan_row(view.left, view.right, g, d_min, d_max, min_score=0.6)
            if not peak.ok:
                raise MultiviewError(f"view {view.name}: the added point {p.tolist()} has no stereo match")
            found.append(peak.shift)
        new = triangulate(geo, added, added - np.column_stack([found, np.zeros(len(found))]))
        points = np.vstack([points, new.points_cam])
        uv = np.vstack([uv, added])
        desc = np.vstack([desc, describe_at(view.left, added, settings.detector).astype(desc.dtype)])
    segments = stereo_segments(view.left, view.right, geo, min_length_px=settings.min_length_px,
                               max_range=settings.max_range)
    for pixel in edits.remove_edges:
        if segments:
            segments.pop(int(np.argmin([_distance_to_segment(pixel, s.uv_left) for s in segments])))
    for edge in edits.add_edges:
        seg = _edge_at(view, geo, edge, settings)
        if seg is None:
            raise MultiviewError(f"view {view.name}: the added edge {edge.tolist()} has no stereo match")
        segments.append(seg)
    return points, uv, desc, segments


def _edge_at(view: ViewInput, geo: RectifiedStereo, edge: Array, settings: FormationSettings) -> Segment | None:
    d_min, d_max = geo.disparity_range(0.5, settings.max_range)
    best = None
    for side in (1.0, -1.0):
        disp, scores, ok = match_end_points(view.left, view.right, edge, side, d_min, d_max, 0.6)
        if ok and (best is None or disp.mean() > best[0].mean()):
            best = (disp, scores, side)
    if best is None:
        return None
    return segment_from_disparities(geo, edge, best[0], best[2], best[1])


def _distance_to_segment(p: Array, uv: Array) -> float:
    d = uv[1] - uv[0]
    t = float(np.clip((p - uv[0]) @ d / max(float(d @ d), 1e-9), 0.0, 1.0))
    return float(np.linalg.norm(p - (uv[0] + t * d)))


def choose_base(segments: list[Segment], z_world_cam: Array, pick: Array | None) -> Segment:
    """The operator's base segment (the edge nearest both picked ends), else the longest near-horizontal one."""
    if not segments:
        raise MultiviewError("the base view has no segment line to build the object frame on")
    if pick is not None:
        cost = [min(np.linalg.norm(s.uv_left - pick, axis=1).sum(),
                    np.linalg.norm(s.uv_left[::-1] - pick, axis=1).sum()) for s in segments]
        return segments[int(np.argmin(cost))]
    tilt = [np.degrees(np.arcsin(min(1.0, abs(float((s.points[1] - s.points[0]) @ z_world_cam)) / s.length)))
            for s in segments]
    flat = [s for s, t in zip(segments, tilt, strict=True) if t <= MAX_BASE_TILT_DEG]
    if not flat:
        raise MultiviewError("no near-horizontal segment line for the base: pick one in the edits")
    return max(flat, key=lambda s: s.length)


def build_model(object_id: str, views: list[ViewInput], edits: Edits | None = None,
                settings: FormationSettings | None = None, T_world_database: Array | None = None) -> ObjectModel:
    """The multi-view model of an object from overview views (see the module docstring). `T_world_database` is
    the object's database pose, for `T_database_object` (by the navigation poses)."""
    if not views:
        raise MultiviewError("a model needs at least one view")
    edits = edits or Edits()
    settings = settings or FormationSettings()
    names = [v.name for v in views]
    if edits.base_view is not None and edits.base_view not in names:
        raise MultiviewError(f"the base view {edits.base_view} is not among the views ({', '.join(names)})")
    base_index = names.index(edits.base_view) if edits.base_view is not None else 0
    order = [base_index] + [i for i in range(len(views)) if i != base_index]
    elements = {i: view_elements(views[i], settings, edits.for_view(views[i].name)) for i in order}
    base_view = views[base_index]
    z_world_cam = base_view.T_world_cam_nav[2, :3]          # world z in the base camera frame (nav attitude)
    base = choose_base(elements[base_index][3], z_world_cam, edits.base_edge)
    T_base_object = object_frame(base.points[0], base.points[1], z_world_cam)
    T_object_view = {base_index: invert(T_base_object)}
    links: list[tuple[int, int, int, int]] = []
    for i in order[1:]:
        placed = sorted(T_object_view, key=lambda j: float(np.linalg.norm(
            views[j].T_world_cam_nav[:3, 3] - views[i].T_world_cam_nav[:3, 3])))
        for j in placed:                                   # stage 1 between two views: T_viewj_viewi
            m = match_points(elements[j][0], elements[j][2], elements[i][0], elements[i][2], settings.tolerance)
            if m.ok and m.matched >= 6:
                T_object_view[i] = T_object_view[j] @ m.T_view_work
                break
        else:                                              # the navigation estimate places it
            j = placed[0]
            T_object_view[i] = T_object_view[j] @ invert(views[j].T_world_cam_nav) @ views[i].T_world_cam_nav
    for a in order:                                        # every pair's matches tie points for averaging
        for b in order:
            if a < b:
                m = match_points(elements[a][0], elements[a][2], elements[b][0], elements[b][2], settings.tolerance)
                links += [(a, int(p), b, int(q)) for p, q in m.pairs]
    view_models = []
    for i, v in enumerate(views):
        pts, uv, desc, segs = elements[i]
        view_models.append(ViewModel(v.name, np.asarray(v.K, float), float(v.baseline), v.left,
                                     np.asarray(v.T_world_cam_nav, float), T_object_view[i], pts, uv, desc, segs,
                                     find_corners(segs)))
    model = ObjectModel(object_id, view_models, settings.detector,
                        transform_points(T_object_view[base_index], base.points))
    merge_full_model(model, links, settings.merge_tol)
    if T_world_database is not None:
        model.T_database_object = (invert(np.asarray(T_world_database, float)) @ base_view.T_world_cam_nav
                                   @ T_base_object)
    return model


def extend_model(model: ObjectModel, views: list[ViewInput], settings: FormationSettings | None = None) -> ObjectModel:
    """A model extended by the views of a later run (seed 000 §3.1, last paragraph): each new view is placed by
    stage-1 matching against the model's views (nearest first) and the full model is averaged again."""
    settings = settings or FormationSettings(detector=model.detector)  # type: ignore[arg-type]
    old = list(model.views)
    links: list[tuple[int, int, int, int]] = []
    new_views: list[ViewModel] = []
    for v in views:
        pts, uv, desc, segs = view_elements(v, settings, ViewEdits())
        near = sorted(range(len(old)), key=lambda j: float(np.linalg.norm(
            old[j].T_world_view_nav[:3, 3] - v.T_world_cam_nav[:3, 3])))
        T = None
        for j in near:
            m = match_points(old[j].points, old[j].descriptors, pts, desc, settings.tolerance)
            if m.ok and m.matched >= 6:
                T = old[j].T_object_view @ m.T_view_work
                links += [(j, int(p), len(old) + len(new_views), int(q)) for p, q in m.pairs]
                break
        if T is None:
            raise MultiviewError(f"view {v.name} matches none of the model's views: it cannot extend the model")
        new_views.append(ViewModel(v.name, np.asarray(v.K, float), float(v.baseline), v.left,
                                   np.asarray(v.T_world_cam_nav, float), T, pts, uv, desc, segs, find_corners(segs)))
    # Links among the old views, recomputed from their stored points.
    for a in range(len(old)):
        for b in range(a + 1, len(old)):
            m = match_points(old[a].points, old[a].descriptors, old[b].points, old[b].descriptors, settings.tolerance)
            links += [(a, int(p), b, int(q)) for p, q in m.pairs]
    out = ObjectModel(model.object_id, old + new_views, model.detector, model.base_segment,
                      T_database_object=model.T_database_object)
    merge_full_model(out, links, settings.merge_tol)
    return out


__all__ = ["FormationSettings", "ViewInput", "build_model", "choose_base", "describe_at", "extend_model",
           "view_elements"]
