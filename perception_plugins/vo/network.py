"""The virtual reference network of seed 003 ("Учет самопересечений траектории", Fig. 4–5).

Reference frames are fixed every `every` frames along the trajectory; each keeps what the seed lists: the stereo
pair (as its stereo features — Harris corners with ORB descriptors — and their triangulated points, which is all
the binding uses), its pose, its chain of local transforms, and the seabed area it saw (its keyframe's
triangulated points, in its camera frame). At every new fragment start the odometer offers the position to the
network. If the position's view overlaps a reference's by at least `overlap` (the share of the position's points,
placed by the current pose estimate, that fall inside the reference's image in front of it) and the reference's
chain is shorter, the position is bound to it: features are matched between the two pairs, T_ref_cur follows from
PnP-RANSAC and the four-image refinement, and the position's chain is replaced by the reference's chain plus that
one transform. A new reference made at a bound position therefore carries the shorter chain. References are made
during the first `formation_frames` frames (all along when None), and after that only at bound positions.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mission.geometry import invert, transform_points
from mission.plugin_api import StereoImages
from perception_plugins.stereo import Cloud
from perception_plugins.vo.chain import Chain
from perception_plugins.vo.classic import describe, match_descriptors
from perception_plugins.vo.frontend import Array
from perception_plugins.vo.motion import estimate_motion


@dataclass(frozen=True)
class NetworkSettings:
    every: int = 8
    """Frames between reference frames."""
    overlap: float = 0.5
    """Smallest share of the view in common with a reference for binding."""
    min_inliers: int = 40
    """Features a binding needs."""
    chain_margin: int = 2
    """Bind only to references whose chain is shorter by more than this many transforms."""
    formation_frames: int | None = None
    max_correction: float = 0.5
    """Largest jump a binding may make, as a share of the view's median depth (guards against false matches)."""
    features: int = 1500
    tries: int = 2


@dataclass(frozen=True, eq=False)
class Reference:
    """A reference frame of the network."""

    index: int
    chain: Chain
    cloud: Cloud
    """Stereo features of its pair (Harris corners, ORB descriptors) and their points in its camera frame."""
    view_points: Array
    """The part of the seabed it saw: triangulated points in its camera frame."""
    K: Array
    image_size: tuple[int, int]

    @property
    def T_origin_ref(self) -> Array:
        return self.chain.pose()


@dataclass(frozen=True, eq=False)
class Binding:
    reference: int
    chain: Chain
    inliers: int


def view_overlap(reference: Reference, T_origin_cur: Array, points_cur: Array) -> float:
    """The share of the current view's points that the reference camera sees (inside its image, in front)."""
    if len(points_cur) == 0:
        return 0.0
    p = transform_points(invert(reference.T_origin_ref) @ T_origin_cur, points_cur)
    K, (w, h) = reference.K, reference.image_size
    z = p[:, 2]
    front = z > 1e-3
    u = K[0, 0] * p[:, 0] / np.where(front, z, 1.0) + K[0, 2]
    v = K[1, 1] * p[:, 1] / np.where(front, z, 1.0) + K[1, 2]
    inside = front & (u >= 0) & (u <= w - 1) & (v >= 0) & (v <= h - 1)
    return float(inside.mean())


class ReferenceNetwork:
    """The reference frames and the binding to them (see the module docstring)."""

    def __init__(self, settings: NetworkSettings | None = None) -> None:
        self.settings = settings or NetworkSettings()
        self.references: list[Reference] = []
        self.bindings = 0
        self.attempts = 0
        self.used: set[int] = set()

    def offer(self, index: int, frame: StereoImages, chain: Chain, points_cam: Array) -> Binding | None:
        """Bind this position to a reference when possible, and make it a reference when due; returns the binding."""
        s = self.settings
        cloud: Cloud | None = None
        binding = None
        T_origin_cur = chain.pose()
        candidates = [(view_overlap(r, T_origin_cur, points_cam), r) for r in self.references
                      if r.chain.length + 1 + s.chain_margin < chain.length]
        candidates = sorted([c for c in candidates if c[0] >= s.overlap], key=lambda c: (-c[0], c[1].chain.length))
        depth = float(np.median(points_cam[:, 2])) if len(points_cam) else 1.0
        for _, ref in candidates[:s.tries]:
            if cloud is None:
                cloud = describe(frame, s.features)
            binding = self._bind(ref, frame, cloud, T_origin_cur, s.max_correction * depth)
            if binding is not None:
                break
        last = self.references[-1].index if self.references else None
        forming = s.formation_frames is None or index <= s.formation_frames
        if (last is None or index - last >= s.every) and (forming or binding is not None):
            if cloud is None:
                cloud = describe(frame, s.features)
            h, w = frame.left.shape[:2]
            self.references.append(Reference(index, binding.chain if binding else chain, cloud, points_cam.copy(),
                                             frame.K.copy(), (w, h)))
        return binding

    def _bind(self, ref: Reference, frame: StereoImages, cloud: Cloud, T_origin_cur: Array,
              max_jump: float) -> Binding | None:
        self.attempts += 1
        ia, ib = match_descriptors(ref.cloud.descriptors, cloud.descriptors)
        if len(ia) < self.settings.min_inliers:
            return None
        T_ref_cur_pred = invert(ref.T_origin_ref) @ T_origin_cur
        motion = estimate_motion(ref.cloud.points_cam[ia], cloud.uv_left[ib], frame.K, uv_b_right=cloud.uv_right[ib],
                                 baseline=frame.baseline)
        if motion is None or motion.count < self.settings.min_inliers:
            return None
        if np.linalg.norm(motion.T_a_b[:3, 3] - T_ref_cur_pred[:3, 3]) > max_jump:
            return None
        self.bindings += 1
        self.used.add(ref.index)
        return Binding(ref.index, ref.chain.append(motion.T_a_b), motion.count)


__all__ = ["Binding", "NetworkSettings", "Reference", "ReferenceNetwork", "view_overlap"]
