"""Three-stage recognition and referencing with a multi-view model (seed 000 §3.2).

Views are chosen by proximity (the navigation position of the working camera to each view's). Stage 1 (points,
`points.match_points`) gives each view's matched points and H_work_view; stage 2 (`lines.recognise_lines`) the
view's segment lines and corners; stage 3 the camera in the object frame by one of the seed's approaches:

- "1": eq. (1), T_object_work = T_object_view · T_view_work of the view with the most matched points;
- "2a": eq. (2), one least-squares transform from every view's matched points, model side in the object frame;
- "2b": eq. (5), as 2a plus the end points of recognised lines and the points of recognised corners;
- "3": eq. (6), each view's eq. (1) camera position averaged with weights α_k ∝ np_k (the rotation is the
  weighted chordal mean of theirs, which the seed does not need since it reports positions).

The recognition table (seed Table 1) gives, per view, matched/total points, lines and corners. Identification
criteria (stated here, the seed leaves them open): some view matched at least `min_points` points, or at least
`min_points_with_lines` points and one recognised line, and the fused transform fits its points within the
tolerance (RMS).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from mission.geometry import transform_points
from perception_plugins.multiview.errors import MultiviewError
from perception_plugins.multiview.lines import LineMatch, LineSettings, recognise_lines
from perception_plugins.multiview.model import ObjectModel, ViewModel
from perception_plugins.multiview.points import PointMatch, match_points, weighted_fit
from perception_plugins.referencing.transform import robust_rigid_transform
from perception_plugins.stereo.camera import RectifiedStereo
from perception_plugins.stereo.pipeline import stereo_cloud
from perception_plugins.stereo.triangulation import Cloud

Array = NDArray[np.float64]
Image = NDArray[np.uint8]
Approach = Literal["1", "2a", "2b", "3"]
APPROACHES: tuple[Approach, ...] = ("1", "2a", "2b", "3")


@dataclass(frozen=True)
class RecognitionSettings:
    views: int = 3
    approach: Approach = "2b"
    tolerance: float = 0.06
    max_features: int = 1500
    max_range: float = 10.0
    lines: LineSettings = field(default_factory=LineSettings)
    min_points: int = 6
    min_points_with_lines: int = 4


@dataclass(frozen=True)
class ViewResult:
    """Stages 1–2 for one view and its eq. (1) transform."""

    view: ViewModel
    points: PointMatch
    lines: LineMatch | None
    T_object_work: Array | None

    def row(self) -> dict[str, object]:
        v = self.view
        lines = 0 if self.lines is None else len(self.lines.segments)
        corners = 0 if self.lines is None else len(self.lines.corners)
        return {"view": v.name, "points": [self.points.matched, len(v.points)],
                "lines": [lines, len(v.segments)], "corners": [corners, len(v.corners)]}


@dataclass(frozen=True)
class Recognition:
    """The outcome: identification decision, the camera in the object frame (None when not identified)."""

    identified: bool
    reason: str
    approach: Approach
    T_object_work: Array | None
    views: list[ViewResult]
    rms: float = float("nan")
    cloud_points: int = 0

    @property
    def table(self) -> list[dict[str, object]]:
        return [v.row() for v in self.views]

    @property
    def matched_points(self) -> int:
        """Working points matched to any view, duplicates counted once."""
        used = {int(j) for v in self.views for j in v.points.pairs[:, 1]}
        return len(used)

    @property
    def matched_lines(self) -> int:
        return sum(0 if v.lines is None else len(v.lines.segments) for v in self.views)

    @property
    def matched_corners(self) -> int:
        return sum(0 if v.lines is None else len(v.lines.corners) for v in self.views)

    def summary(self) -> dict[str, object]:
        return {"identified": self.identified, "reason": self.reason, "approach": self.approach,
                "views": [v.view.name for v in self.views], "matched_points": self.matched_points,
                "matched_lines": self.matched_lines, "matched_corners": self.matched_corners,
                "rms_m": None if not np.isfinite(self.rms) else round(float(self.rms), 4), "table": self.table}


def choose_views(model: ObjectModel, T_world_cam_nav: Array | None, count: int,
                 T_object_cam_prior: Array | None = None) -> list[ViewModel]:
    """The `count` views whose camera positions are nearest the working camera's: in the world by navigation,
    or else in the object frame by a prior (in model order without either)."""
    if T_world_cam_nav is not None:
        where = np.asarray(T_world_cam_nav, float)[:3, 3]
        return sorted(model.views, key=lambda v: float(np.linalg.norm(v.T_world_view_nav[:3, 3] - where)))[:count]
    if T_object_cam_prior is not None:
        at = np.asarray(T_object_cam_prior, float)[:3, 3]
        return sorted(model.views, key=lambda v: float(np.linalg.norm(v.T_object_view[:3, 3] - at)))[:count]
    return model.views[:count]


def view_stages(view: ViewModel, cloud: Cloud, left: Image, right: Image, geo: RectifiedStereo,
                settings: RecognitionSettings, with_lines: bool = True) -> ViewResult:
    """Stages 1 and 2 against one view."""
    pm = match_points(view.points, view.descriptors, cloud.points_cam, cloud.descriptors, settings.tolerance)
    if not pm.ok:
        return ViewResult(view, pm, None, None)
    lines = recognise_lines(view, pm.T_view_work, left, right, geo, settings.lines) if with_lines else None
    return ViewResult(view, pm, lines, view.T_object_view @ pm.T_view_work)


def fuse(results: list[ViewResult], cloud: Cloud, approach: Approach, tolerance: float) -> tuple[Array | None, float]:
    """Stage 3: T_object_work by the approach, and the RMS residual of the points it used (m)."""
    ok = [r for r in results if r.T_object_work is not None]
    if not ok:
        return None, float("inf")
    if approach == "1":
        best = max(ok, key=lambda r: r.points.matched)
        return best.T_object_work, best.points.rms
    if approach == "3":
        w = np.array([r.points.matched for r in ok], dtype=float)
        w /= w.sum()
        Ts = [r.T_object_work for r in ok if r.T_object_work is not None]
        T = np.eye(4)
        T[:3, 3] = np.sum([wk * Tk[:3, 3] for wk, Tk in zip(w, Ts, strict=True)], axis=0)
        u, _, vt = np.linalg.svd(np.sum([wk * Tk[:3, :3] for wk, Tk in zip(w, Ts, strict=True)], axis=0))
        T[:3, :3] = u @ np.diag([1.0, 1.0, np.linalg.det(u @ vt)]) @ vt
        return T, float(np.average([r.points.rms for r in ok], weights=w))
    src, dst, z_src, z_dst = [], [], [], []
    for r in ok:
        T_ov = r.view.T_object_view
        pairs = r.points.pairs
        parts = [(cloud.points_cam[pairs[:, 1]], r.view.points[pairs[:, 0]])]
        if approach == "2b" and r.lines is not None:
            parts += [(r.lines.work_points.reshape(-1, 3), r.lines.view_points.reshape(-1, 3)),
                      (r.lines.corner_work_points.reshape(-1, 3), r.lines.corner_view_points.reshape(-1, 3))]
        for work, view in parts:
            src.append(work)
            dst.append(transform_points(T_ov, view))
            z_src.append(work[:, 2])
            z_dst.append(view[:, 2])
    S, D = np.vstack(src), np.vstack(dst)
    fit = robust_rigid_transform(S, D, threshold=tolerance, max_rejected=0.3)
    keep = fit.inliers
    T = weighted_fit(S[keep], D[keep], np.concatenate(z_src)[keep], np.concatenate(z_dst)[keep])
    return T, fit.rms


def recognise(model: ObjectModel, left: Image, right: Image, K: Array, baseline: float,
              T_world_cam_nav: Array | None = None, settings: RecognitionSettings | None = None,
              cloud: Cloud | None = None, T_object_cam_prior: Array | None = None) -> Recognition:
    """Recognise the object in a working pair and reference the camera to it (see the module docstring)."""
    settings = settings or RecognitionSettings()
    if settings.approach not in APPROACHES:
        raise MultiviewError(f"unknown approach {settings.approach!r} (available: {', '.join(APPROACHES)})")
    h, w = left.shape[:2]
    geo = RectifiedStereo.from_K(K, baseline, (w, h))
    if cloud is None:
        cloud = stereo_cloud(left, right, geo, model.detector, settings.max_features,  # type: ignore[arg-type]
                             max_range=settings.max_range)
    views = choose_views(model, T_world_cam_nav, settings.views, T_object_cam_prior)
    with_lines = settings.approach == "2b"
    results = [view_stages(v, cloud, left, right, geo, settings, with_lines) for v in views]
    T, rms = fuse(results, cloud, settings.approach, settings.tolerance)
    identified, reason = decide(results, T, rms, settings)
    return Recognition(identified, reason, settings.approach, T if identified else None, results, rms, len(cloud))


def decide(results: list[ViewResult], T: Array | None, rms: float, settings: RecognitionSettings
           ) -> tuple[bool, str]:
    """The identification decision from the recognition table (criteria in the module docstring)."""
    best_points = max((r.points.matched for r in results), default=0)
    lines = sum(0 if r.lines is None else len(r.lines.segments) for r in results)
    if T is None:
        return False, "no view matched three points"
    if not (best_points >= settings.min_points
            or (best_points >= settings.min_points_with_lines and lines >= 1)):
        return False, (f"too few elements: {best_points} points (need {settings.min_points}, or "
                       f"{settings.min_points_with_lines} with a line), {lines} lines")
    if not rms <= settings.tolerance:
        return False, f"residual {rms:.3f} m above the tolerance"
    return True, f"{best_points} points in the best view, {lines} lines"

__all__ = ["APPROACHES", "Approach", "Recognition", "RecognitionSettings", "ViewResult", "choose_views", "decide",
           "fuse", "recognise", "view_stages"]
