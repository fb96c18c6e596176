"""The world as a MuJoCo model: one static model per scene that the sonar ray-casts and the cameras render.

Seed 002 §2.1 surveys the seabed with a multibeam echo-sounder whose beams are "ray-cast against the world"; the
stereo cameras render the same world. Both go through this module: the seabed height field
becomes an `hfield` geom and every object part a box or cylinder geom, all static in the worldbody.

Frames. Our world is local NED (north, east, down = depth). MuJoCo is right-handed and z-up, so the model is
built in ENU: MuJoCo x = east, y = north, z = −depth. The map is a proper rotation (det +1) and its own inverse
(swap the first two axes, negate the third), so points and directions convert the same way:

>>> import numpy as np
>>> ned_to_mj(np.array([10.0, 20.0, 50.0])).tolist()
[20.0, 10.0, -50.0]
>>> mj_to_ned(ned_to_mj(np.array([[1.0, 2.0, 3.0]]))).tolist()
[[1.0, 2.0, 3.0]]

MuJoCo's hfield conventions: `size = (radius_x, radius_y, elevation_z, base_z)`, the field spans
[−radius, +radius] about the geom position, data are normalised to [0, 1] and scaled by `elevation_z`, and data
row r (of `nrow`) lies at y = −radius_y + r·2·radius_y/(nrow − 1), column c at x likewise. Our `depth[i, j]`
(north index i, east index j) therefore maps to row i, column j directly, with the geom at the field's lowest
point (z = −max depth), shifted by `HFIELD_JITTER` cells (see there). MuJoCo triangulates each cell, so between
grid nodes the surface is piecewise planar where `HeightField.depth_at` is bilinear; at the nodes both agree
(up to float32 storage).

Geom groups: the seabed is in `SEABED_GROUP`, objects in `OBJECT_GROUP`, so a ray cast can ignore either. Object
geoms are named `"<object id>/<part index>"`; `MjWorld.object_of_geom` attributes a hit to its object.

Appearance (for cameras, `MjWorld(scene, appearance=Appearance(...))`): see `mission.sim.textures` for the
textures and `mission.sim.meshes` for the textured twins of the parts.

An `MjData` is not thread-safe: give each thread its own `MjWorld` (or its own `mujoco.MjData`).
"""

from __future__ import annotations

from collections import OrderedDict
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from mission.frames import Array, rotation_zyx
from mission.language.world import Box, Cylinder, Part
from mission.sim.meshes import box_mesh, cylinder_mesh
from mission.sim.texture_cache import object_texels, seabed_texels
from mission.sim.textures import Appearance
from mission.world.scene import PlacedObject, Scene
from mission.world.terrain import HeightField

SEABED_GROUP = 0
OBJECT_GROUP = 1
VISUAL_GROUP = 2
"""Textured twins of the object parts, for cameras only (present with an `Appearance`)."""
SEABED_TILE_GROUP = 3
"""The seabed again, in square tiles, for cameras only: a camera draws the tiles it can see, not the whole field."""
HIDDEN_GROUP = 5
"""A group no camera or ray shows: cameras park the tiles they cannot see here."""

# Columns: NED axes expressed in MuJoCo's ENU world (x = east, y = north, z = up = −down).
R_MJ_NED: Array = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
R_NED_MJ: Array = R_MJ_NED.T

# MuJoCo 4.0's hfield ray test misses the terrain (and reports the base plane at the lowest elevation) for rays
# lying exactly, to ~1e-13 m, in the vertical plane of a grid row or of a cell diagonal: a fan at heading 0 from
# a whole-metre north on a 1 m grid does that. Shifting the field by a few micro-cells (east, north) moves those
# planes off round coordinates; the depth error this introduces is the shift times the slope, below 1e-6 m.
HFIELD_JITTER: Array = np.array([2.9e-6, 1.3e-6])

# Part axes in the object frame for a cylinder whose axis is x, y or z (MuJoCo cylinders run along local z).
_CYLINDER_AXIS: dict[str, Array] = {
    "x": rotation_zyx(0.0, 90.0, 0.0),   # local z → object x
    "y": rotation_zyx(0.0, 0.0, -90.0),  # local z → object y
    "z": np.eye(3),
}


def ned_to_mj(points_ned: Array) -> Array:
    """(…, 3) NED points (north, east, down) → MuJoCo world points (east, north, up)."""
    p = np.asarray(points_ned, dtype=float)
    return np.stack([p[..., 1], p[..., 0], -p[..., 2]], axis=-1)


def mj_to_ned(points_mj: Array) -> Array:
    """(…, 3) MuJoCo world points (east, north, up) → NED points (north, east, down)."""
    p = np.asarray(points_mj, dtype=float)
    return np.stack([p[..., 1], p[..., 0], -p[..., 2]], axis=-1)


def ned_dir_to_mj(directions_ned: Array) -> Array:
    """Directions (free vectors) NED → MuJoCo; the map is linear, so the same as for points."""
    return ned_to_mj(directions_ned)


def mj_dir_to_ned(directions_mj: Array) -> Array:
    """Directions (free vectors) MuJoCo → NED."""
    return mj_to_ned(directions_mj)


def _fmt(values: Any) -> str:
    return " ".join(repr(float(v)) for v in np.ravel(values))


def _part_rotation_object(part: Part) -> Array:
    """R_object_part: the MuJoCo geom's local axes in the object frame."""
    if isinstance(part, Box):
        return rotation_zyx(part.heading)
    assert isinstance(part, Cylinder)
    return _CYLINDER_AXIS[part.axis]


def _part_pose_mj(obj: PlacedObject, part: Part) -> tuple[Array, Array]:
    """A part's geom position and quaternion in MuJoCo's world."""
    T = obj.T_world_object
    R_world_part = T[:3, :3] @ _part_rotation_object(part)
    pos_ned = T[:3, :3] @ np.asarray(part.at, dtype=float) + T[:3, 3]
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, (R_MJ_NED @ R_world_part).ravel())
    return ned_to_mj(pos_ned), quat


def _part_geom_xml(obj: PlacedObject, index: int, part: Part) -> str:
    pos, quat = _part_pose_mj(obj, part)
    if isinstance(part, Box):
        kind, size = "box", 0.5 * np.asarray(part.size, dtype=float)
    else:
        kind, size = "cylinder", np.array([part.radius, 0.5 * part.height])
    rgba = (*part.color, 1.0)
    return (f'<geom name="{obj.id}/{index}" type="{kind}" size="{_fmt(size)}" pos="{_fmt(pos)}" '
            f'quat="{_fmt(quat)}" group="{OBJECT_GROUP}" rgba="{_fmt(rgba)}" contype="0" conaffinity="0"/>')


def _hfield_layout(field: HeightField) -> tuple[Array, Array, NDArray[np.float32]]:
    """(geom position in MuJoCo, hfield size, normalised data rows × cols) for a height field."""
    z = -field.depth
    z_lo, z_hi = float(z.min()), float(z.max())
    elevation = max(z_hi - z_lo, 1e-3)  # MuJoCo wants a positive elevation even for a flat seabed
    rx = 0.5 * (field.east_max - field.east0)
    ry = 0.5 * (field.north_max - field.north0)
    jitter = field.resolution * HFIELD_JITTER
    pos = np.array([field.east0 + rx + jitter[0], field.north0 + ry + jitter[1], z_lo])
    size = np.array([rx, ry, elevation, 1.0])
    data = ((z - z_lo) / elevation).astype(np.float32)
    return pos, size, data


def _visual_xml(obj: PlacedObject, index: int, part: Part, tile_m: float, rng: np.random.Generator
                ) -> tuple[str, str]:
    """(asset XML, worldbody XML) of a part's textured twin: a mesh with the primitive's shape, pose and colour."""
    name = f"vis/{obj.id}/{index}"
    offset = rng.uniform(0.0, tile_m, size=(6, 2))  # so that faces of equal size do not look alike
    if isinstance(part, Box):
        verts, normals, uvs, faces = box_mesh(0.5 * np.asarray(part.size, dtype=float), offset)
    else:
        verts, normals, uvs, faces = cylinder_mesh(part.radius, 0.5 * part.height, offset)
    asset = (f'<mesh name="{name}" vertex="{_fmt(verts)}" normal="{_fmt(normals)}" '
             f'texcoord="{_fmt(uvs / tile_m)}" face="{" ".join(str(int(f)) for f in faces.ravel())}"/>\n    '
             f'<material name="{name}" texture="objects" rgba="{_fmt((*part.color, 1.0))}" specular="0.1" '
             f'shininess="0.2"/>')
    pos, quat = _part_pose_mj(obj, part)
    body = (f'<geom name="{name}" type="mesh" mesh="{name}" material="{name}" pos="{_fmt(pos)}" '
            f'quat="{_fmt(quat)}" group="{VISUAL_GROUP}" contype="0" conaffinity="0"/>')
    return asset, body


def seabed_tiles(field: HeightField, cells: int) -> list[HeightField]:
    """The height field cut into square tiles of `cells` cells a side that share their border nodes; tiles at the
    far edges are padded with the edge's depths so that every tile has the same size."""
    rows, cols = field.depth.shape
    tiles = []
    for i0 in range(0, max(rows - 1, 1), cells):
        for j0 in range(0, max(cols - 1, 1), cells):
            ii = np.minimum(np.arange(i0, i0 + cells + 1), rows - 1)
            jj = np.minimum(np.arange(j0, j0 + cells + 1), cols - 1)
            tiles.append(HeightField(np.ascontiguousarray(field.depth[np.ix_(ii, jj)]),
                                     field.north0 + i0 * field.resolution, field.east0 + j0 * field.resolution,
                                     field.resolution))
    return tiles


def build_model_xml(scene: Scene, offscreen: tuple[int, int] = (1280, 960), near_m: float = 0.05,
                    far_m: float = 400.0, appearance: Appearance | None = None, offsamples: int = 4) -> str:
    """The MJCF of a scene, with the hfield's shape but not its data (set `hfield_data` after compiling);
    `offsamples`: multisamples per pixel of the off-screen buffer (MuJoCo's default 4; 0 renders without
    anti-aliasing, about half the cost on a software renderer).

    With an `appearance`, textures are declared at their size but filled after compiling (`MjWorld` does both),
    and every object part gets its textured twin in `VISUAL_GROUP`.
    """
    field = scene.seabed
    pos, size, _ = _hfield_layout(field)
    rows, cols = field.depth.shape
    extent = float(max(2.0 * size[0], 2.0 * size[1], 1.0))
    centre = pos + np.array([0.0, 0.0, 0.5 * size[2]])
    geoms = [_part_geom_xml(obj, k, placed.part) for obj in scene.objects for k, placed in enumerate(obj.parts)]
    nl = "\n    "
    if appearance is None:
        # A checker repeating every 2 m: enough to see the seabed in a debugging view.
        repeat = (2.0 * size[0] / 2.0, 2.0 * size[1] / 2.0)
        textures = ('<texture name="seabed" type="2d" builtin="checker" rgb1="0.55 0.5 0.4" rgb2="0.45 0.42 0.34"'
                    ' width="256" height="256"/>')
        assets: list[str] = []
    else:
        cells, periods, _ = appearance.tiling(field.resolution)
        n, m = appearance.seabed_texels, appearance.object_texels
        repeat = (periods, periods)
        textures = (f'<texture name="seabed" type="2d" builtin="flat" rgb1="0.5 0.5 0.5" width="{n}" height="{n}"/>'
                    f'{nl}<texture name="objects" type="2d" builtin="flat" rgb1="0.8 0.8 0.8" width="{m}" '
                    f'height="{m}"/>')
        rng = np.random.default_rng(appearance.object_seed)
        twins = [_visual_xml(obj, k, placed.part, appearance.object_tile_m, rng)
                 for obj in scene.objects for k, placed in enumerate(obj.parts)]
        assets = [a for a, _ in twins]
        geoms += [g for _, g in twins]
        for k, tile in enumerate(seabed_tiles(field, cells)):
            tile_pos, tile_size, _ = _hfield_layout(tile)
            assets.append(f'<hfield name="seabed/{k}" nrow="{cells + 1}" ncol="{cells + 1}" size="{_fmt(tile_size)}"/>')
            geoms.append(f'<geom name="seabed/{k}" type="hfield" hfield="seabed/{k}" pos="{_fmt(tile_pos)}" '
                         f'material="seabed" group="{SEABED_TILE_GROUP}" contype="0" conaffinity="0"/>')
    return f"""<mujoco model="{scene.name}">
  <statistic center="{_fmt(centre)}" extent="{extent!r}"/>
  <visual>
    <global offwidth="{offscreen[0]}" offheight="{offscreen[1]}"/>
    <quality shadowsize="0" offsamples="{offsamples}"/>
    <map znear="{near_m / extent!r}" zfar="{far_m / extent!r}"/>
    <headlight ambient="0.3 0.3 0.3" diffuse="0.4 0.4 0.4" specular="0 0 0"/>
  </visual>
  <asset>
    <hfield name="seabed" nrow="{rows}" ncol="{cols}" size="{_fmt(size)}"/>
    {textures}
    <material name="seabed" texture="seabed" texrepeat="{_fmt(repeat)}" specular="0" shininess="0"/>
    {nl.join(assets)}
  </asset>
  <worldbody>
    <light name="sun" type="directional" castshadow="false" pos="{_fmt(centre + [0, 0, 100])}" dir="0 0 -1"/>
    <geom name="seabed" type="hfield" hfield="seabed" pos="{_fmt(pos)}" material="seabed"
          group="{SEABED_GROUP}" contype="0" conaffinity="0"/>
    {nl.join(geoms)}
  </worldbody>
</mujoco>
"""


class MjWorld:
    """A scene compiled into a MuJoCo model and data, ready for ray casts and off-screen rendering.

    Build it once per scene (or use `mjworld_for`, which caches): compiling the reference world takes a fraction
    of a second, a ray fan takes well under a millisecond.
    """

    def __init__(self, scene: Scene, offscreen: tuple[int, int] = (1280, 960), near_m: float = 0.05,
                 far_m: float = 400.0, appearance: Appearance | None = None, offsamples: int = 4) -> None:
        self.scene = scene
        self.appearance = appearance
        self.model = mujoco.MjModel.from_xml_string(build_model_xml(scene, offscreen, near_m, far_m, appearance,
                                                                    offsamples))
        _, _, data = _hfield_layout(scene.seabed)
        adr = int(self.model.hfield("seabed").adr[0])
        self.model.hfield_data[adr:adr + data.size] = data.ravel()
        self.seabed_tile_geoms: NDArray[np.int_] = np.zeros(0, dtype=int)
        """Geom ids of the seabed tiles (with an appearance)."""
        self.seabed_tile_centres: Array = np.zeros((0, 3))
        """(T, 3) centres of the tiles' bounding spheres, MuJoCo world coordinates."""
        self.seabed_tile_radii: Array = np.zeros(0)
        """(T,) radii of the tiles' bounding spheres (m)."""
        if appearance is not None:
            a = appearance
            self._fill_tiles(a.tiling(scene.seabed.resolution)[0])
            self._fill_texture("seabed", seabed_texels(a.seabed, a.seabed_texels, a.seabed_tile_m))
            self._fill_texture("objects", object_texels(a.object_seed, a.object_texels, a.object_tile_m))
        self.data = mujoco.MjData(self.model)
        mujoco.mj_kinematics(self.model, self.data)  # static geoms get their world poses in geom_xpos/xmat
        self.seabed_geom = int(self.model.geom("seabed").id)
        names = [""] * self.model.ngeom
        parts = np.full(self.model.ngeom, -1, dtype=int)
        for obj in scene.objects:
            for k in range(len(obj.parts)):
                gid = int(self.model.geom(f"{obj.id}/{k}").id)
                names[gid], parts[gid] = obj.id, k
        self.object_of_geom: NDArray[np.str_] = np.array(names, dtype=str)
        """Object id per geom id ("" for the seabed)."""
        self.part_of_geom: NDArray[np.int_] = parts
        """Part index per geom id (−1 for the seabed)."""
        # Index with geomid + 1 so that "no hit" (−1) maps to "".
        self._object_by_hit = np.concatenate([np.array([""], dtype=self.object_of_geom.dtype), self.object_of_geom])

    def _fill_tiles(self, cells: int) -> None:
        ids, centres, radii = [], [], []
        for k, tile in enumerate(seabed_tiles(self.scene.seabed, cells)):
            hfield = self.model.hfield(f"seabed/{k}")
            _, size, data = _hfield_layout(tile)
            adr = int(hfield.adr[0])
            self.model.hfield_data[adr:adr + data.size] = data.ravel()
            geom = self.model.geom(f"seabed/{k}")
            ids.append(int(geom.id))
            centres.append(geom.pos + np.array([0.0, 0.0, 0.5 * size[2]]))
            radii.append(float(np.linalg.norm(size[:3] * [1.0, 1.0, 0.5])))
        self.seabed_tile_geoms = np.array(ids, dtype=int)
        self.seabed_tile_centres, self.seabed_tile_radii = np.array(centres), np.array(radii)

    def _fill_texture(self, name: str, rgb: NDArray[np.uint8]) -> None:
        tex = self.model.texture(name)
        adr, count = int(tex.adr[0]), int(tex.width[0] * tex.height[0] * tex.nchannel[0])
        assert rgb.size == count, (name, rgb.shape, count)
        self.model.tex_data[adr:adr + count] = rgb.ravel()

    def group_mask(self, seabed: bool = True, objects: bool = True) -> NDArray[np.uint8]:
        """The `geomgroup` argument of MuJoCo's ray functions: 1 = the group is seen."""
        mask = np.zeros(6, dtype=np.uint8)
        mask[SEABED_GROUP] = seabed
        mask[OBJECT_GROUP] = objects
        return mask

    def cast_fan(self, origin_ned: Array, directions_ned: Array, cutoff: float, seabed: bool = True,
                 objects: bool = True) -> tuple[Array, NDArray[np.int32]]:
        """Cast rays from one point in one `mj_multiRay` call.

        `directions_ned` (N, 3) must be unit vectors; returns (distance in metres, −1 for no hit; geom id, −1 for
        no hit). Geoms farther than `cutoff` are skipped, but a hit beyond it may still be reported.
        """
        dirs = np.ascontiguousarray(ned_dir_to_mj(directions_ned).reshape(-1))
        n = dirs.size // 3
        dist = np.empty(n, dtype=np.float64)
        geomid = np.empty(n, dtype=np.int32)
        mujoco.mj_multiRay(self.model, self.data, ned_to_mj(origin_ned).reshape(3), dirs,
                           self.group_mask(seabed, objects), True, -1, geomid, dist, None, n, float(cutoff))
        return dist, geomid

    def objects_hit(self, geomid: NDArray[np.int32]) -> NDArray[np.str_]:
        """Object id for each geom id of a ray cast ("" for the seabed or no hit)."""
        return np.asarray(self._object_by_hit[np.asarray(geomid) + 1])


_CACHE: OrderedDict[int, MjWorld] = OrderedDict()  # by id(scene): a Scene holds arrays and is unhashable
_CACHE_SIZE = 4


def mjworld_for(scene: Scene) -> MjWorld:
    """The `MjWorld` of a scene, compiled once; the last few scenes' models are kept (each keeps its scene alive,
    so an id is never reused while cached)."""
    world = _CACHE.get(id(scene))
    if world is not None and world.scene is scene:
        _CACHE.move_to_end(id(scene))
        return world
    world = MjWorld(scene)
    _CACHE[id(scene)] = world
    while len(_CACHE) > _CACHE_SIZE:
        _CACHE.popitem(last=False)
    return world


__all__ = ["Appearance", "HIDDEN_GROUP", "MjWorld", "OBJECT_GROUP", "R_MJ_NED", "R_NED_MJ", "SEABED_GROUP",
           "SEABED_TILE_GROUP", "VISUAL_GROUP", "build_model_xml", "mj_dir_to_ned", "mj_to_ned",
           "mjworld_for", "ned_dir_to_mj", "ned_to_mj", "seabed_tiles"]
