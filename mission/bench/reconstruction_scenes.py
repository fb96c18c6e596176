"""Scenes of `auv bench reconstruction`: three objects composed of boxes and cylinders (as in
`worlds/sps_field.yaml`) on a flat textured seabed, the views around each at explore range, the navigation noise
added to those views' poses, and the exact geometry to score a mesh against.

The truth is analytic: the signed distance of the union of the parts and the seabed plane (boxes and cylinders in
their own frames), so the mesh → truth distance is exact; completeness samples the parts' faces and drops the
samples buried in the seabed, inside another part or on a face in contact with one (the exposed surface).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mission.frames import pose_matrix
from mission.language.world import Box, Cylinder, World

Array = NDArray[np.float64]
SEABED_DEPTH = 30.0
"""Depth of the flat seabed (m); every object stands on it."""

SHAPES: dict[str, list[dict[str, Any]]] = {
    # worlds/sps_field.yaml's wellhead protection structure (its base frame rests on the seabed).
    "wellhead-x": [
        {"shape": "box", "size": [4, 4, 0.4], "at": [0, 0, -0.2], "color": [0.5, 0.5, 0.5]},
        {"shape": "cylinder", "radius": 0.6, "height": 2.6, "at": [0, 0, -1.7]},
        {"shape": "box", "size": [1.6, 0.4, 0.4], "at": [0.9, 0, -2.2]},
    ],
    # A manifold module on its skid, a valve drum lying across it and a lifting point on the roof.
    "manifold-module": [
        {"shape": "box", "size": [4, 3, 0.4], "at": [0, 0, -0.2], "color": [0.45, 0.38, 0.12]},
        {"shape": "box", "size": [2, 1.6, 1.2], "at": [-0.6, 0, -1.0], "color": [0.95, 0.85, 0.3]},
        {"shape": "cylinder", "radius": 0.3, "height": 1.2, "axis": "y", "at": [1.2, 0, -0.7]},
        {"shape": "box", "size": [0.4, 0.4, 0.4], "at": [-0.6, 0, -1.8]},
    ],
    # A pipeline spool on two sleepers, with a flange ring and a riser stub.
    "pipe-spool": [
        {"shape": "box", "size": [0.5, 1.6, 0.4], "at": [-1.2, 0, -0.2], "color": [0.4, 0.4, 0.35]},
        {"shape": "box", "size": [0.5, 1.6, 0.4], "at": [1.2, 0, -0.2], "color": [0.4, 0.4, 0.35]},
        {"shape": "cylinder", "radius": 0.35, "height": 4.0, "axis": "x", "at": [0, 0, -0.75]},
        {"shape": "cylinder", "radius": 0.5, "height": 0.2, "axis": "x", "at": [0.3, 0, -0.75]},
        {"shape": "cylinder", "radius": 0.2, "height": 1.0, "at": [-1.6, 0, -1.4]},
    ],
}


def scene_world(name: str, heading: float = 20.0) -> World:
    """A world holding one object of `SHAPES` at the origin on a flat seabed."""
    return World.model_validate({
        "name": f"recon-{name}",
        "seabed": {"north": [-25, 25], "east": [-25, 25], "resolution": 0.5, "mean_depth": SEABED_DEPTH,
                   "roughness": {"amplitude": 0.0}, "texture": {"kind": "sand", "seed": 5}},
        "objects": [{"id": name, "pose": {"north": 0, "east": 0, "depth": SEABED_DEPTH, "heading": heading},
                     "parts": SHAPES[name]}],
    })


def look_at(position: Array, target: Array) -> Array:
    """T_world_cam of a camera at `position` looking at `target` (OpenCV axes, image y towards world down)."""
    z = target - position
    z = z / np.linalg.norm(z)
    down = np.array([0.0, 0.0, 1.0])
    y = down - (down @ z) * z
    if np.linalg.norm(y) < 1e-6:
        y = np.array([1.0, 0.0, 0.0]) - z[0] * z
    y = y / np.linalg.norm(y)
    T = np.eye(4)
    T[:3, 0], T[:3, 1], T[:3, 2], T[:3, 3] = np.cross(y, z), y, z, position
    return T


def ring_views(target: Array, distance: float, rings: tuple[tuple[float, int], ...],
               start_deg: float = 10.0) -> list[Array]:
    """Cameras on rings around `target`: (elevation° above horizontal, count) each, looking at it."""
    views = []
    for k, (elevation, count) in enumerate(rings):
        e = math.radians(elevation)
        for i in range(count):
            a = math.radians(start_deg + 360.0 * i / count + 17.0 * k)
            offset = np.array([-math.cos(e) * math.cos(a), -math.cos(e) * math.sin(a), -math.sin(e)])
            views.append(look_at(target + distance * offset, target))
    return views


def noisy_poses(poses: list[Array], seed: int, heading_sigma_deg: float = 0.3, depth_sigma_m: float = 0.02,
                drift_fraction: float = 0.005) -> list[Array]:
    """The poses as navigation would give them (`mission.sim.vehicle`'s noise levels): heading noise per frame,
    depth-sensor noise per frame, and a horizontal random walk of `drift_fraction` of each leg (DVL drift)."""
    rng = np.random.default_rng(seed)
    drift = np.zeros(3)
    out = []
    for i, T in enumerate(poses):
        if i:
            leg = float(np.linalg.norm(T[:2, 3] - poses[i - 1][:2, 3]))
            drift[:2] += rng.normal(0.0, drift_fraction * leg / math.sqrt(2.0), 2)
        Rz = pose_matrix(0.0, 0.0, 0.0, float(rng.normal(0.0, heading_sigma_deg)))[:3, :3]
        noisy = np.eye(4)
        noisy[:3, :3] = Rz @ T[:3, :3]
        noisy[:3, 3] = T[:3, 3] + drift + (0.0, 0.0, float(rng.normal(0.0, depth_sigma_m)))
        out.append(noisy)
    return out


@dataclass(frozen=True)
class TruthPart:
    T_world_part: Array
    """Part frame → world: the part's centre, its axes (a cylinder's along local z)."""
    half: Array
    """Box half sizes, or (radius, radius, half height) of a cylinder."""
    cylinder: bool


def truth_parts(world: World) -> list[TruthPart]:
    from mission.world.scene import true_pose

    obj = world.objects[0]
    T_obj = true_pose(obj)
    parts = []
    for p in obj.parts:
        T = np.eye(4)
        T[:3, 3] = p.at
        if isinstance(p, Box):
            T[:3, :3] = pose_matrix(0.0, 0.0, 0.0, p.heading)[:3, :3]
            parts.append(TruthPart(T_obj @ T, np.array(p.size) / 2.0, False))
        else:
            assert isinstance(p, Cylinder)
            axes = {"x": np.array([[0, 0, 1], [0, 1, 0], [-1, 0, 0]]).T, "y": np.array([[1, 0, 0], [0, 0, 1],
                    [0, -1, 0]]).T, "z": np.eye(3)}
            T[:3, :3] = axes[p.axis]
            parts.append(TruthPart(T_obj @ T, np.array([p.radius, p.radius, p.height / 2.0]), True))
    return parts


def part_sdf(part: TruthPart, points: Array) -> Array:
    """Signed distance (m, negative inside) of points to one part."""
    q = (points - part.T_world_part[:3, 3]) @ part.T_world_part[:3, :3]
    if part.cylinder:
        d = np.column_stack([np.hypot(q[:, 0], q[:, 1]) - part.half[0], np.abs(q[:, 2]) - part.half[2]])
    else:
        d = np.abs(q) - part.half
    outside = np.linalg.norm(np.maximum(d, 0.0), axis=1)
    return np.asarray(outside + np.minimum(d.max(axis=1), 0.0))


def truth_sdf(parts: list[TruthPart], points: Array) -> Array:
    """Signed distance to the union of the parts and the seabed (below SEABED_DEPTH is inside)."""
    sdf = SEABED_DEPTH - points[:, 2]
    for part in parts:
        sdf = np.minimum(sdf, part_sdf(part, points))
    return np.asarray(sdf)


def exposed_surface(parts: list[TruthPart], spacing: float = 0.01, seed: int = 0) -> Array:
    """Points every ~`spacing` m over the parts' surfaces that lie neither in the seabed nor inside another part."""
    rng = np.random.default_rng(seed)
    samples = []
    for n, part in enumerate(parts):
        h = part.half
        if part.cylinder:
            r, hz = h[0], h[2]
            area_side, area_cap = 2 * math.pi * r * 2 * hz, math.pi * r * r
            k = int(area_side / spacing**2)
            a, z = rng.uniform(0, 2 * math.pi, k), rng.uniform(-hz, hz, k)
            local = [np.column_stack([r * np.cos(a), r * np.sin(a), z])]
            for sign in (-1.0, 1.0):
                k = int(area_cap / spacing**2)
                rr, a = r * np.sqrt(rng.random(k)), rng.uniform(0, 2 * math.pi, k)
                local.append(np.column_stack([rr * np.cos(a), rr * np.sin(a), np.full(k, sign * hz)]))
        else:
            local = []
            for axis in range(3):
                u, v = [i for i in range(3) if i != axis]
                k = int(4 * h[u] * h[v] / spacing**2)
                for sign in (-1.0, 1.0):
                    pts = np.zeros((k, 3))
                    pts[:, u], pts[:, v] = rng.uniform(-h[u], h[u], k), rng.uniform(-h[v], h[v], k)
                    pts[:, axis] = sign * h[axis]
                    local.append(pts)
        world_pts = np.vstack(local) @ part.T_world_part[:3, :3].T + part.T_world_part[:3, 3]
        # Strictly outside the seabed and every other part: faces in contact (a part standing on another, a base
        # on the seabed) are buried, not exposed.
        keep = world_pts[:, 2] < SEABED_DEPTH - 2e-3
        for m, other in enumerate(parts):
            if m != n:
                keep &= part_sdf(other, world_pts) > 2e-3
        samples.append(world_pts[keep])
    return np.vstack(samples)


__all__ = ["SEABED_DEPTH", "SHAPES", "TruthPart", "exposed_surface", "look_at", "noisy_poses", "part_sdf",
           "ring_views", "scene_world", "truth_parts", "truth_sdf"]
