"""The `multiview-referencing` perception plug-in: a stereo pair in, the camera's pose in the object's database
frame out, by three-stage recognition against the object's multi-view model (seed 000 §3.2).

`configure(settings)` reads `settings["models"]` (object id → model file: what a mission's `objects[].model`
names, `mission.plugin_settings`) and `settings["multiview"]`: `views` (how many views to compare, default 3),
`approach` ("1", "2a", "2b" or "3"; default "2b") and, optionally, more `models`. A request names the object
through its point sets; the prior T_cam_object (database frame) chooses the views nearest the camera. The result's
transform is expressed in the database frame through the model's `T_database_object`; `details` hold the
approach, the elements matched (`elements`: points, lines, corners), the recognition table (`table`) and the
identification decision (`decision`, or `reason` when the object is not recognised).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from mission.geometry import invert, transform_points
from mission.plugin_api import ReferencingRequest, ReferencingResult, StereoImages
from perception_plugins.multiview.errors import MultiviewError
from perception_plugins.multiview.model import ObjectModel
from perception_plugins.multiview.model_io import read_model
from perception_plugins.multiview.recognition import APPROACHES, RecognitionSettings, recognise
from perception_plugins.stereo.camera import RectifiedStereo
from perception_plugins.stereo.pipeline import stereo_cloud


class MultiviewReferencingPlugin:
    """Entry point `multiview-referencing` (group `auv.perception`)."""

    def __init__(self) -> None:
        self.paths: dict[str, Path] = {}
        self.models: dict[str, ObjectModel] = {}
        self.settings = RecognitionSettings()

    def configure(self, settings: Mapping[str, Any]) -> None:
        own = settings.get("multiview") or {}
        models = {**(settings.get("models") or {}), **(own.get("models") or {})}
        self.paths = {str(k): Path(v) for k, v in models.items()}
        approach = str(own.get("approach", self.settings.approach))
        if approach not in APPROACHES:
            raise MultiviewError(f"unknown approach {approach!r} (available: {', '.join(APPROACHES)})")
        self.settings = RecognitionSettings(views=int(own.get("views", self.settings.views)),
                                            approach=approach)  # type: ignore[arg-type,unused-ignore]

    def reset(self) -> None:
        return None

    def close(self) -> None:
        self.models.clear()

    def _model(self, object_id: str) -> ObjectModel:
        if object_id not in self.models:
            if object_id not in self.paths:
                raise MultiviewError(f"no multi-view model configured for object '{object_id}'")
            self.models[object_id] = read_model(self.paths[object_id])
        return self.models[object_id]

    def process(self, frame: StereoImages, request: ReferencingRequest) -> ReferencingResult:
        if not request.sets:
            return ReferencingResult.not_recognised("no object requested")
        model = self._model(request.sets[0].object_id)
        T_db_object = model.T_database_object
        prior = None
        if request.prior_T_cam_object is not None:            # camera in the model's object frame
            prior = invert(T_db_object) @ invert(np.asarray(request.prior_T_cam_object, float))
        h, w = frame.left.shape[:2]
        geo = RectifiedStereo.from_K(frame.K, frame.baseline, (w, h))
        cloud = stereo_cloud(frame.left, frame.right, geo, model.detector,  # type: ignore[arg-type]
                             self.settings.max_features, max_range=self.settings.max_range)
        r = recognise(model, frame.left, frame.right, frame.K, frame.baseline, None, self.settings, cloud=cloud,
                      T_object_cam_prior=prior)
        details: dict[str, Any] = {"method": "multiview", **r.summary(),
                                   "elements": {"points": r.matched_points, "lines": r.matched_lines,
                                                "corners": r.matched_corners}}
        if not r.identified or r.T_object_work is None:
            return ReferencingResult(False, cloud_points=r.cloud_points, details={"reason": r.reason, **details})
        T_cam_db = invert(T_db_object @ r.T_object_work)
        model_pts, cam_pts = [], []
        for v in r.views:
            pairs = v.points.pairs
            if len(pairs):
                model_pts.append(transform_points(T_db_object @ v.view.T_object_view, v.view.points[pairs[:, 0]]))
                cam_pts.append(cloud.points_cam[pairs[:, 1]])
        details["model"] = str(self.paths[model.object_id])
        details["decision"] = details.pop("reason")  # a "reason" is what an agent reports for a failure
        set_id = visible_set(request, T_cam_db, frame.K, (w, h))
        return ReferencingResult(True, set_id, T_cam_db, r.matched_points, r.rms, False,
                                 r.cloud_points, details, np.vstack(model_pts), np.vstack(cam_pts))


def visible_set(request: ReferencingRequest, T_cam_object: np.ndarray, K: np.ndarray, size: tuple[int, int]) -> str:
    """The requested point set the referenced camera sees best: the most points inside the image, then the
    nearest the image centre (the model recognises the object, not a set, but an agent hovers over a set).

    >>> from mission.plugin_api import PointSetModel
    >>> sets = (PointSetModel("o", "far", np.array([[9.0, 0, 4], [9, 1, 4], [10, 0, 4]])),
    ...         PointSetModel("o", "near", np.array([[0.0, 0, 4], [0.5, 0, 4], [0, 0.5, 4]])))
    >>> K = np.array([[500.0, 0, 320], [0, 500, 240], [0, 0, 1]])
    >>> visible_set(ReferencingRequest(sets), np.eye(4), K, (640, 480))
    'near'
    """
    w, h = size
    best: tuple[int, float, str] | None = None
    for pset in request.sets:
        cam = transform_points(T_cam_object, np.asarray(pset.points, float))
        z = np.maximum(cam[:, 2], 1e-6)
        uv = (cam[:, :2] / z[:, None]) * [K[0, 0], K[1, 1]] + [K[0, 2], K[1, 2]]
        inside = int(np.sum((cam[:, 2] > 0) & (uv[:, 0] >= 0) & (uv[:, 0] < w) & (uv[:, 1] >= 0) & (uv[:, 1] < h)))
        off = float(np.mean(np.linalg.norm(uv - [w / 2, h / 2], axis=1)))
        if best is None or (inside, -off) > (best[0], -best[1]):
            best = (inside, off, pset.set_id)
    assert best is not None
    return best[2]


__all__ = ["MultiviewReferencingPlugin", "visible_set"]
