"""The truth's stereo coverage of an explored object (issue 22, the explore planner's `reconstruct` goal): the
share of the object's TRUE exposed surface that the stereo pairs recorded during the element saw within the
useful range and at most `planners.nbv.MAX_INCIDENCE_DEG` off the surface normal, from the TRUE camera poses
(`SimulatedVehicle.log.frames`), against the TRUE geometry.

The surface is sampled every `SPACING_M` on the parts' faces (boxes: six faces; cylinders: side and caps), with
the rule of `explore_metrics.surface_points` (not inside another part, not in contact with the seabed), so the
share of samples is the share of area. A sample is seen from a pair when it lies in the left camera's frustum,
between the camera's nearest and useful range, at incidence ≤ 60°, and is not hidden by the object itself: every
sample is splatted into a coarse depth buffer of the view (`BUFFER_PX` pixels a side at most, and no pixel
smaller than 1.5 sample spacings at the nearest sample, so that a face has no holes), and a sample farther than
`DEPTH_TOLERANCE_M` behind the nearest sample of its pixel is hidden. The seabed hides nothing here (samples in
contact with it are not counted).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from mission.sim.explore_metrics import CONTACT_M, distance_to_part, local_samples, part_frame
from mission.world.scene import PlacedObject, Scene

Array = NDArray[np.float64]
SPACING_M = 0.05
BUFFER_PX = 160
DEPTH_TOLERANCE_M = 0.08
MAX_INCIDENCE_DEG = 60.0  # as planners.nbv.MAX_INCIDENCE_DEG (the simulator does not import planners)


def surface_samples(obj: PlacedObject, scene: Scene, spacing: float = SPACING_M) -> tuple[Array, Array]:
    """World points on the object's exposed surface and their outward normals (world frame)."""
    pts_out, nrm_out = [], []
    for k, placed in enumerate(obj.parts):
        R, c = part_frame(obj, placed.part)
        local, normals = local_samples(placed.part, spacing)
        pts, nrm = local @ R.T + c, normals @ R.T
        for j, other in enumerate(obj.parts):
            if j != k:
                keep = distance_to_part(pts, obj, other.part) > 1e-6
                pts, nrm = pts[keep], nrm[keep]
        pts_out.append(pts)
        nrm_out.append(nrm)
    pts = np.concatenate(pts_out) if pts_out else np.zeros((0, 3))
    nrm = np.concatenate(nrm_out) if nrm_out else np.zeros((0, 3))
    keep = pts[:, 2] < scene.seabed.depths_at(pts[:, 0], pts[:, 1]) - CONTACT_M
    return pts[keep], nrm[keep]


def seen_by_view(points: Array, normals: Array, T_world_cam: Array, fov_deg: tuple[float, float],
                 useful_range: float, min_range: float) -> NDArray[np.bool_]:
    """(N,) whether each sample is seen well from one camera pose (the module docstring's rule)."""
    R, t = T_world_cam[:3, :3], T_world_cam[:3, 3]
    v = points - t
    dist = np.linalg.norm(v, axis=1)
    c = v @ R
    z = c[:, 2]
    th, tv = (math.tan(math.radians(a) / 2.0) for a in fov_deg)
    inside = (z > 1e-6) & (np.abs(c[:, 0]) <= th * z) & (np.abs(c[:, 1]) <= tv * z)
    facing = -(v * normals).sum(axis=1) / np.maximum(dist, 1e-9)
    ok = inside & (dist >= min_range) & (dist <= useful_range) & (facing >= math.cos(math.radians(MAX_INCIDENCE_DEG)))
    if not ok.any():
        return np.asarray(ok)
    # Depth buffer of every sample in front of the camera (facing or not: a part's back face hides nothing that
    # its front face does not, and the front face is sampled too).
    front = inside & (z > 0.1)
    # Pixels no smaller than 1.5 sample spacings at the nearest sample, so that a near face has no holes.
    scale = min(BUFFER_PX / max(2.0 * th, 2.0 * tv), float(z[front].min()) / (1.5 * SPACING_M))
    px = np.floor((c[front, 0] / z[front] + th) * scale).astype(np.int64)
    py = np.floor((c[front, 1] / z[front] + tv) * scale).astype(np.int64)
    w, h = int(math.ceil(2.0 * th * scale)) + 1, int(math.ceil(2.0 * tv * scale)) + 1
    buffer = np.full(w * h, np.inf)
    np.minimum.at(buffer, py * w + px, z[front])
    index = np.full(len(points), -1, dtype=np.int64)
    index[front] = py * w + px
    ok[ok] = z[ok] <= buffer[index[ok]] + DEPTH_TOLERANCE_M
    return np.asarray(ok)


def stereo_coverage(obj: PlacedObject, scene: Scene, poses: list[Array], fov_deg: tuple[float, float],
                    useful_range: float, min_range: float) -> tuple[float, int]:
    """The share (0–1) of the object's true surface samples seen well from at least one of the true left-camera
    poses T_world_left, and the number of poses that saw any."""
    points, normals = surface_samples(obj, scene)
    if not len(points):
        return 0.0, 0
    seen = np.zeros(len(points), dtype=bool)
    useful_views = 0
    for T in poses:
        s = seen_by_view(points, normals, np.asarray(T, dtype=np.float64), fov_deg, useful_range, min_range)
        useful_views += int(s.any())
        seen |= s
    return float(seen.mean()), useful_views
