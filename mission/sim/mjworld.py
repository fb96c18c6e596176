"""The world as a MuJoCo model: one static model per scene that the sonar ray-casts and the cameras render.

Seed 002 §2.1 surveys the seabed with a multibeam echo-sounder whose beams are "ray-cast against the world"; the
stereo cameras of a later issue render the same world. Both go through this module: the seabed height field
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

An `MjData` is not thread-safe: give each thread its own `MjWorld` (or its own `mujoco.MjData`).
"""

from __future__ import annotations

from collections import OrderedDict
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from mission.frames import Array, rotation_zyx
from mission.world.model import Box, Cylinder, Part
from mission.world.scene import PlacedObject, Scene
from mission.world.terrain import HeightField

SEABED_GROUP = 0
OBJECT_GROUP = 1

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


def _part_geom_xml(obj: PlacedObject, index: int, part: Part) -> str:
    T = obj.T_world_object
    R_world_part = T[:3, :3] @ _part_rotation_object(part)
    pos_ned = T[:3, :3] @ np.asarray(part.at, dtype=float) + T[:3, 3]
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, (R_MJ_NED @ R_world_part).ravel())
    if isinstance(part, Box):
        kind, size = "box", 0.5 * np.asarray(part.size, dtype=float)
    else:
        kind, size = "cylinder", np.array([part.radius, 0.5 * part.height])
    rgba = (*part.color, 1.0)
    return (f'<geom name="{obj.id}/{index}" type="{kind}" size="{_fmt(size)}" pos="{_fmt(ned_to_mj(pos_ned))}" '
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


def build_model_xml(scene: Scene, offscreen: tuple[int, int] = (1280, 960), near_m: float = 0.05,
                    far_m: float = 400.0) -> str:
    """The MJCF of a scene, with the hfield's shape but not its data (set `hfield_data` after compiling)."""
    field = scene.seabed
    pos, size, _ = _hfield_layout(field)
    rows, cols = field.depth.shape
    extent = float(max(2.0 * size[0], 2.0 * size[1], 1.0))
    centre = pos + np.array([0.0, 0.0, 0.5 * size[2]])
    geoms = [_part_geom_xml(obj, k, placed.part) for obj in scene.objects for k, placed in enumerate(obj.parts)]
    # The texture repeats every 2 m on the seabed; a procedural seabed texture replaces the checker later.
    repeat = (2.0 * size[0] / 2.0, 2.0 * size[1] / 2.0)
    nl = "\n    "
    return f"""<mujoco model="{scene.name}">
  <statistic center="{_fmt(centre)}" extent="{extent!r}"/>
  <visual>
    <global offwidth="{offscreen[0]}" offheight="{offscreen[1]}"/>
    <quality shadowsize="0"/>
    <map znear="{near_m / extent!r}" zfar="{far_m / extent!r}"/>
    <headlight ambient="0.3 0.3 0.3" diffuse="0.4 0.4 0.4" specular="0 0 0"/>
  </visual>
  <asset>
    <hfield name="seabed" nrow="{rows}" ncol="{cols}" size="{_fmt(size)}"/>
    <texture name="seabed" type="2d" builtin="checker" rgb1="0.55 0.5 0.4" rgb2="0.45 0.42 0.34"
             width="256" height="256"/>
    <material name="seabed" texture="seabed" texrepeat="{_fmt(repeat)}" specular="0" shininess="0"/>
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
                 far_m: float = 400.0) -> None:
        self.scene = scene
        self.model = mujoco.MjModel.from_xml_string(build_model_xml(scene, offscreen, near_m, far_m))
        _, _, data = _hfield_layout(scene.seabed)
        self.model.hfield_data[:] = data.ravel()
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


__all__ = ["MjWorld", "OBJECT_GROUP", "R_MJ_NED", "R_NED_MJ", "SEABED_GROUP", "build_model_xml", "mj_dir_to_ned",
           "mj_to_ned", "mjworld_for", "ned_dir_to_mj", "ned_to_mj"]
