"""The `stereo-referencing` perception plug-in: a stereo pair in, the camera's pose in the object frame out
(seed 002 §3.1–3.3, the three-stage scheme).

1. Harris corners of both rectified images are matched along epipolar lines, refined to sub-pixel and
   triangulated into a 3D cloud in the left camera frame (object corners and seabed points alike).
2. Each requested characteristic-point set is identified in the cloud by structural coherence
   (`perception_plugins.referencing.reference`), ambiguities settled by the prior. When it is not, and the prior
   is tight (`guided_radius_m`; `guided: false` turns it off), corners looked for where the prior puts the set's
   points (`perception_plugins.referencing.guided`) join the cloud and the identification runs again; the result
   says so (`details["guided"]`): its points are less precise (up to 6 cm against 0.5–2.5 cm), and a fix that
   fuses views prefers the others.
3. The least-squares transform of the identified points gives T_cam_object. A result that puts the object far
   from where the prior (database pose + navigation) says is refused as implausible: outliers can fake
   consistent sets, and the database is "off by metres", not by tens of metres. So is one that tilts the
   object's vertical axis away from the prior's by more than `gate_tilt_deg`: structures rest on the seabed
   (the database's z is the world's, seed 000 §3.1), and a wrong correspondence of a flat set fits by tilting it
   (a skid's four points matched 17° tilted, three views agreeing, would fly the vehicle into the module).
   And so is one that moves the set up or down by more than `gate_depth_m` along the prior's vertical: the
   database's depth and the depth sensor place a structure on the seabed within a metre, while its position may be
   metres off. A rectangle of corners (a module's top) fits the dense points of flat seabed texture just as well
   as the module; such a fix puts the object its own height too deep, and flying by it takes the vehicle down
   beside the module it thinks it is above (measured: 2.4–2.8 m too deep in every wrong module-top fix of two
   seeded runs, 0.2 m for the right ones).

The consistency tolerance grows with range like the stereo depth error (σ_Z ∝ Z²).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from mission.geometry import rotation_angle_deg, transform_points
from mission.plugin_api import ReferencingRequest, ReferencingResult, StereoImages
from perception_plugins.referencing.guided import guided_corners
from perception_plugins.referencing.identification import reference
from perception_plugins.stereo.camera import RectifiedStereo
from perception_plugins.stereo.pipeline import stereo_cloud

REFERENCE_RANGE_M = 3.6  # the range at which the request's tolerance applies (seed 000's virtual scene)
MAX_FEATURES = 600
"""Harris corners kept per image by default (`referencing.max_features` overrides it)."""


class StereoReferencingPlugin:
    """Entry point `stereo-referencing` (group `auv.perception`)."""

    def __init__(self) -> None:
        self.max_range = 8.0
        self.max_features = MAX_FEATURES
        self.gate_m = 5.0
        self.gate_deg = 25.0
        self.gate_tilt_deg = 6.0
        self.gate_depth_m = 1.0
        self.guided = True
        self.guided_radius_m = 1.0

    def configure(self, settings: Mapping[str, Any]) -> None:
        stereo = (settings.get("sensors") or {}).get("stereo") or {}
        self.max_range = float(stereo.get("max_range", self.max_range))
        own = settings.get("referencing") or {}
        self.max_features = int(own.get("max_features", self.max_features))
        self.gate_m = float(own.get("gate_m", self.gate_m))
        self.gate_deg = float(own.get("gate_deg", self.gate_deg))
        self.gate_tilt_deg = float(own.get("gate_tilt_deg", self.gate_tilt_deg))
        self.gate_depth_m = float(own.get("gate_depth_m", self.gate_depth_m))
        self.guided = bool(own.get("guided", self.guided))
        self.guided_radius_m = float(own.get("guided_radius_m", self.guided_radius_m))

    def reset(self) -> None:
        return None

    def close(self) -> None:
        return None

    @staticmethod
    def _with_guided(frame: StereoImages, candidates: np.ndarray, predicted: np.ndarray, radius: float
                     ) -> np.ndarray:
        """The candidates plus the guided corners near the predicted points (`guided`); a guided corner within
        3 cm of a candidate is the same corner, and the candidate (matched and refined over the whole image) is
        kept."""
        guided = guided_corners(frame.left, frame.right, frame.K, frame.baseline, predicted, radius).points_cam
        if not len(guided):
            return candidates
        if len(candidates):
            gap = np.min(np.linalg.norm(guided[:, None, :] - candidates[None, :, :], axis=2), axis=1)
            guided = guided[gap > 0.03]
        return np.vstack([candidates, guided])

    def process(self, frame: StereoImages, request: ReferencingRequest) -> ReferencingResult:
        height, width = frame.left.shape[:2]
        geometry = RectifiedStereo.from_K(frame.K, frame.baseline, (width, height))
        cloud = stereo_cloud(frame.left, frame.right, geometry, detector="harris", max_features=self.max_features,
                             max_range=self.max_range)
        points = cloud.points_cam
        if len(points) < 3:
            return ReferencingResult(False, cloud_points=len(points), details={"reason": "fewer than 3 points"})
        best: ReferencingResult | None = None
        refused: list[str] = []
        for model in request.sets:
            tolerance = request.tolerance
            prior = request.prior_T_cam_object
            if prior is not None:
                predicted = transform_points(prior, model.points)
                ranges = predicted[:, 2]
                tolerance *= max(1.0, (float(np.max(ranges)) / REFERENCE_RANGE_M) ** 2)
            candidates = points
            radius = request.prior_radius
            guided = False
            if prior is not None and request.prior_radius is not None:
                near = np.min(np.linalg.norm(points[:, None, :] - predicted[None, :, :], axis=2), axis=1)
                candidates = points[near <= request.prior_radius]
                guided = self.guided and radius is not None and radius <= self.guided_radius_m
            found = reference(model.points, candidates, tolerance, prior) if len(candidates) >= 3 else None
            with_guided = False
            if guided and radius is not None and (found is None or not found.recognised):
                # Guided corners only when the whole-image cloud does not hold the set: where it does, its
                # points are the more precise (measured: single views 0.5-2.5 cm off, up to 6 cm with guided ones).
                candidates = self._with_guided(frame, candidates, predicted, radius)
                found = reference(model.points, candidates, tolerance, prior) if len(candidates) >= 3 else None
                with_guided = True
            found_points = candidates
            if found is None or not found.recognised or found.T_cloud_model is None:
                continue
            T = found.T_cloud_model
            if prior is not None:
                shift = float(np.max(np.linalg.norm(
                    transform_points(T, model.points) - transform_points(prior, model.points), axis=1)))
                turn = rotation_angle_deg(T[:3, :3].T @ prior[:3, :3])
                tilt = math.degrees(math.acos(min(1.0, max(-1.0, float(T[:3, 2] @ prior[:3, 2])))))
                if shift > self.gate_m or turn > self.gate_deg:
                    refused.append(f"{model.set_id}: {shift:.1f} m / {turn:.0f} deg from the prior")
                    continue
                if tilt > self.gate_tilt_deg:
                    refused.append(f"{model.set_id}: tilted {tilt:.0f} deg from the prior's vertical")
                    continue
                centre = model.points.mean(axis=0)
                sink = float((T[:3, :3] @ centre + T[:3, 3] - prior[:3, :3] @ centre - prior[:3, 3]) @ prior[:3, 2])
                if abs(sink) > self.gate_depth_m:
                    refused.append(f"{model.set_id}: {abs(sink):.1f} m {'deeper' if sink > 0 else 'shallower'} "
                                   "than the prior")
                    continue
            model_idx = [i for i, _ in found.pairs]
            cloud_idx = [j for _, j in found.pairs]
            result = ReferencingResult(True, model.set_id, T, found.matched, found.residual_rms, found.ambiguous,
                                       len(points), {"method": found.method, "tolerance": tolerance,
                                                     "candidates": len(candidates), "guided": with_guided},
                                       model.points[model_idx], found_points[cloud_idx])
            if best is None or (result.matched, -result.residual_rms) > (best.matched, -best.residual_rms):
                best = result
        if best is None:
            reason = "no set identified" + (f" (implausible: {'; '.join(refused)})" if refused else "")
            return ReferencingResult(False, cloud_points=len(points), details={"reason": reason})
        return best
