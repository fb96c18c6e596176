"""A world made concrete: true object poses, part geometry in the world frame, and a
surface (seabed or object top) that the simulated altimeter sees.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import MultiPoint, Polygon

from mission.frames import Array, pose_matrix, transform_points
from mission.language.world import Box, Cylinder, Part, Texture, World, WorldObject
from mission.world.terrain import HeightField, generate_seabed


@dataclass(frozen=True)
class PlacedPart:
    """One primitive in the world frame: hull corners (north, east, depth), footprint (x = east, y = north), top."""

    part: Part
    corners_world: Array
    footprint: Polygon
    top_depth: float


@dataclass(frozen=True)
class PlacedObject:
    id: str
    database: str | None
    T_world_object: Array
    parts: tuple[PlacedPart, ...]

    @property
    def footprint(self) -> Polygon:
        return shapely.union_all([p.footprint for p in self.parts]).convex_hull

    @property
    def top_depth(self) -> float:
        return min(p.top_depth for p in self.parts)


@dataclass(frozen=True)
class Scene:
    """Everything the simulator knows and the agents do not."""

    name: str
    seabed: HeightField
    surface: HeightField
    current: tuple[float, float]
    objects: tuple[PlacedObject, ...]
    texture: Texture = Texture()  # how the seabed looks to cameras

    def altitude(self, north: float, east: float, depth: float) -> float:
        """Height of a point above whatever lies under it (seabed or an object's top)."""
        return self.surface.depth_at(north, east) - depth


def _part_corners(part: Part) -> Array:
    """Corners of the part's hull in the object frame (cylinders as 16-gons)."""
    cx, cy, cz = part.at
    if isinstance(part, Box):
        length, w, h = part.size
        signs = [(sx, sy, sz) for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]
        local = np.array([[sx * length / 2, sy * w / 2, sz * h / 2] for sx, sy, sz in signs])
        c, s = math.cos(math.radians(part.heading)), math.sin(math.radians(part.heading))
        local = local @ np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]).T
        return np.asarray(local + (cx, cy, cz), dtype=float)
    assert isinstance(part, Cylinder)
    angles = np.linspace(0.0, 2.0 * math.pi, 16, endpoint=False)
    ring = np.stack([part.radius * np.cos(angles), part.radius * np.sin(angles)], axis=1)
    half = part.height / 2
    axis = "xyz".index(part.axis)
    pts = []
    for end in (-half, half):
        p = np.zeros((len(angles), 3))
        others = [k for k in range(3) if k != axis]
        p[:, others[0]], p[:, others[1]] = ring[:, 0], ring[:, 1]
        p[:, axis] = end
        pts.append(p)
    return np.vstack(pts) + (cx, cy, cz)


def true_pose(obj: WorldObject) -> Array:
    """T_world_object of a world object: its charted pose displaced by its offset."""
    p, off = obj.pose, obj.offset
    return pose_matrix(p.north + off.north, p.east + off.east, p.depth + off.depth, p.heading + off.heading,
                       p.pitch + off.pitch, p.roll + off.roll)


def _place(obj: WorldObject, T_world_object: Array) -> PlacedObject:
    parts = []
    for part in obj.parts:
        corners = transform_points(T_world_object, _part_corners(part))
        hull = MultiPoint([(c[1], c[0]) for c in corners]).convex_hull  # x = east, y = north
        parts.append(PlacedPart(part, corners, hull, float(corners[:, 2].min())))
    return PlacedObject(obj.id, obj.database, T_world_object, tuple(parts))


def _raise_surface(surface: Array, field: HeightField, part: PlacedPart) -> None:
    """Lower the surface depth to the part's top over the grid cells its footprint covers."""
    e_lo, n_lo, e_hi, n_hi = part.footprint.bounds
    i0 = max(int(math.floor((n_lo - field.north0) / field.resolution)), 0)
    j0 = max(int(math.floor((e_lo - field.east0) / field.resolution)), 0)
    i1 = min(int(math.ceil((n_hi - field.north0) / field.resolution)), surface.shape[0] - 1)
    j1 = min(int(math.ceil((e_hi - field.east0) / field.resolution)), surface.shape[1] - 1)
    if i1 < i0 or j1 < j0:
        return
    nn, ee = np.meshgrid(field.north0 + field.resolution * np.arange(i0, i1 + 1),
                         field.east0 + field.resolution * np.arange(j0, j1 + 1), indexing="ij")
    inside = shapely.contains_xy(part.footprint.buffer(0.5 * field.resolution), ee, nn)
    block = surface[i0:i1 + 1, j0:j1 + 1]
    block[inside] = np.minimum(block[inside], part.top_depth)


def build_scene(world: World) -> Scene:
    """Place the world's objects and rasterise the surface the altimeter sees."""
    seabed = generate_seabed(world.seabed)
    placed = tuple(_place(o, true_pose(o)) for o in world.objects)
    surface = seabed.depth.copy()
    for obj in placed:
        for part in obj.parts:
            _raise_surface(surface, seabed, part)
    surface_field = HeightField(surface, seabed.north0, seabed.east0, seabed.resolution)
    return Scene(world.name, seabed, surface_field, (world.current.north, world.current.east), placed,
                 world.seabed.texture)
