"""How well a stereo camera has seen the mapped surface, for the explore planner's `reconstruct` goal (issue 22;
seed 003 "3D reconstruction": range maps are only as good as the range and incidence they were taken at).

An occupied voxel of the map is *seen well* from a camera pose when

* it lies in the camera's frustum (the image's field of view, `Camera.fov_deg`),
* between `Camera.min_range` and the useful range, `USEFUL_RANGE_SHARE` × the stereo range: the depth σ of a
  range map, σ_Z = Z²·σ_d / (f·B), grows with the square of the range, so at 0.75 of the range it is 0.56 of
  the σ at the range's end (a 1000 px, 0.25 m rig with σ_d 0.25 px: 3.6 cm at 6 m, 6.4 cm at 8 m),
* at an incidence of at most `MAX_INCIDENCE_DEG` between the viewing ray and the surface normal (the normal from
  the map: the gradient of solid — occupied or unknown — against free space around the voxel; where that gradient
  vanishes the normal is unknown and any incidence passes),
* and no occupied voxel lies between the camera and it, up to two voxels short of it (unknown space is taken as
  clear, as visibility does).

`StereoCoverage` keeps that record over the poses the camera was at; `stereo_gain` counts, for candidate views,
the surface voxels not yet seen well that the camera would see well from them, and `reconstruct_utility` adds it
to the seed's utility. Frames: world NED; a camera's R_world_cam has the image x, image y and optical axis as
columns; the vehicle flies level, so a view's camera is R_world_body(heading) · R_body_cam.

>>> cam = Camera((62.0, 48.5), useful_range=6.0, R_body_cam=np.eye(3)[:, [1, 2, 0]])  # looking ahead
>>> R = camera_rotations(np.array([0.0]), cam.R_body_cam)[0]
>>> pts = np.array([[4.0, 0.0, 0.0], [9.0, 0.0, 0.0], [4.0, 0.0, 0.0]])
>>> normals = np.array([[-1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
>>> seen_from(pts, normals, np.zeros(3), R, cam).tolist()  # in range head-on; beyond range; grazing
[True, False, False]
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from planners.nbv.candidates import is_safe_view
from planners.nbv.grid import FREE, OCCUPIED, StateGrid
from planners.nbv.views import Views
from planners.rrt import ClearanceGrid

Array = NDArray[np.float64]
USEFUL_RANGE_SHARE = 0.75
"""The useful range as a share of the stereo camera's `max_range` (see the module docstring)."""
MAX_INCIDENCE_DEG = 60.0
"""The largest angle between a viewing ray and the surface normal at which a surface counts as seen well."""
OWN_LAYER = 2.0
"""Voxels short of a surface voxel at which the occlusion test stops (`_occluded`)."""
MIN_RANGE_M = 1.5
"""Nearer than this the range maps keep nothing (the disparity search's upper end)."""


@dataclass(frozen=True)
class Camera:
    """A stereo camera as the planner models it: full field of view (horizontal, vertical) in degrees, useful
    range, nearest range, and its fixed mount R_body_cam (columns: image x, image y, optical axis in the body)."""

    fov_deg: tuple[float, float]
    useful_range: float
    R_body_cam: Array
    min_range: float = MIN_RANGE_M

    @classmethod
    def of_stereo(cls, width: int, height: int, fx: float, max_range: float, R_body_cam: ArrayLike) -> Camera:
        """The camera of a pinhole rig `width` × `height` pixels with focal length `fx` (pixels) and range
        `max_range`: useful to `USEFUL_RANGE_SHARE` of it.

        >>> c = Camera.of_stereo(1200, 900, 1000.0, 8.0, np.eye(3))
        >>> [round(a, 1) for a in c.fov_deg], c.useful_range
        ([61.9, 48.5], 6.0)
        """
        fov = (2.0 * math.degrees(math.atan(0.5 * width / fx)), 2.0 * math.degrees(math.atan(0.5 * height / fx)))
        return cls(fov, USEFUL_RANGE_SHARE * max_range, np.asarray(R_body_cam, dtype=float).reshape(3, 3))


def camera_rotations(heading_deg: ArrayLike, R_body_cam: ArrayLike) -> NDArray[np.float64]:
    """R_world_cam (N, 3, 3) of a level vehicle at the given headings (degrees clockwise from north)."""
    h = np.radians(np.asarray(heading_deg, dtype=float).reshape(-1))
    c, s = np.cos(h), np.sin(h)
    R_world_body = np.zeros((len(h), 3, 3))
    R_world_body[:, 0, 0], R_world_body[:, 0, 1] = c, -s
    R_world_body[:, 1, 0], R_world_body[:, 1, 1] = s, c
    R_world_body[:, 2, 2] = 1.0
    return np.asarray(R_world_body @ np.asarray(R_body_cam, dtype=float).reshape(3, 3))


def surface_normals(states: NDArray[np.int8], ijk: ArrayLike) -> Array:
    """Unit outward normals (N, 3) at voxels (N, 3 grid indices): minus the gradient of solid (occupied or
    unknown; outside the grid solid) over the 26 neighbours; zero where the gradient vanishes.

    >>> s = np.full((3, 3, 3), FREE, dtype=np.int8); s[:, :, 2] = OCCUPIED   # a floor at k = 2 (down)
    >>> (surface_normals(s, np.array([[1, 1, 2]])).round(6) + 0.0).tolist()  # its normal points up (−down)
    [[0.0, 0.0, -1.0]]
    """
    idx = np.asarray(ijk, dtype=np.int64).reshape(-1, 3)
    solid = np.pad((states != FREE).astype(np.float32), 1, constant_values=1.0)
    g = np.zeros((len(idx), 3))
    p = idx + 1
    for o in np.stack(np.meshgrid(*[np.arange(-1, 2)] * 3, indexing="ij"), axis=-1).reshape(-1, 3):
        if not o.any():
            continue
        q = p + o
        g += solid[q[:, 0], q[:, 1], q[:, 2]][:, None] * (o / np.linalg.norm(o))[None, :]
    norm = np.linalg.norm(g, axis=1)
    out = np.zeros_like(g)
    ok = norm > 0.5
    out[ok] = -g[ok] / norm[ok, None]
    return out


def seen_from(points: Array, normals: Array, position: ArrayLike, R_world_cam: Array, camera: Camera,
              grid: StateGrid | None = None) -> NDArray[np.bool_]:
    """(N,) whether each surface point (N, 3) with its normal (N, 3; zero: unknown) is seen well from a camera at
    `position` with axes `R_world_cam` (see the module docstring); with `grid`, occupied voxels between the camera
    and the point (more than `OWN_LAYER` voxels short of it) hide it."""
    o = np.asarray(position, dtype=float).reshape(3)
    v = points - o
    dist = np.linalg.norm(v, axis=1)
    c = v @ R_world_cam
    z = c[:, 2]
    th, tv = (math.tan(math.radians(a) / 2.0) for a in camera.fov_deg)
    ok = (z > 1e-9) & (dist >= camera.min_range) & (dist <= camera.useful_range)
    ok &= (np.abs(c[:, 0]) <= th * z) & (np.abs(c[:, 1]) <= tv * z)
    cos_inc = -(v * normals).sum(axis=1) / np.maximum(dist, 1e-9)
    known = np.any(normals != 0.0, axis=1)
    ok &= ~known | (cos_inc >= math.cos(math.radians(MAX_INCIDENCE_DEG)))
    if grid is not None and ok.any():
        ok[ok] = ~_occluded(grid, o, points[ok], dist[ok])
    return np.asarray(ok)


def _occluded(grid: StateGrid, origin: Array, points: Array, dist: Array) -> NDArray[np.bool_]:
    """(N,) whether an occupied voxel lies on the segment from `origin` to each point, stopping `OWN_LAYER`
    voxels short: a ray meeting a face at up to 60° runs through the face's own voxel layer (half a voxel thick,
    plus its staircase) for up to two voxels before the voxel it looks at."""
    step = 0.7 * grid.resolution
    k = max(1, math.ceil(float(dist.max()) / step))
    t = (np.arange(k) + 0.5) * step
    u = (points - origin) / np.maximum(dist, 1e-9)[:, None]
    samples = origin + u[:, :, None].transpose(0, 2, 1) * t[None, :, None]
    before = t[None, :] < (dist[:, None] - OWN_LAYER * grid.resolution)
    states = grid.state(samples.reshape(-1, 3)).reshape(len(points), k)
    return np.asarray(((states == OCCUPIED) & before).any(axis=1))


def stereo_gain(grid: StateGrid, points: Array, normals: Array, positions: Array, R_world_cam: NDArray[np.float64],
                camera: Camera) -> NDArray[np.int64]:
    """(V,) for each candidate camera (positions (V, 3), R_world_cam (V, 3, 3)): how many of the surface points
    (not yet seen well) it would see well."""
    out = np.zeros(len(positions), dtype=np.int64)
    if not len(points):
        return out
    for i in range(len(positions)):
        out[i] = int(seen_from(points, normals, positions[i], R_world_cam[i], camera, grid).sum())
    return out


def camera_candidates(grid: StateGrid, safety: ClearanceGrid, points: Array, normals: Array, camera: Camera, *,
                      count: int, near: float, safe_distance: float, rng: np.random.Generator) -> Views:
    """Up to `count` views that put a surface point (drawn from `points`, those not yet seen well) at the centre of
    the camera's image, between `near` and the useful range, facing it: the heading is the bearing against the
    point's horizontal normal (± 30°; any heading for a point whose normal is near vertical), the position the
    point less the range times the camera's optical axis at that heading. Kept when inside the grid, in free
    space and safe (`is_safe_view`); pitch 0 (the planner's mount sets it)."""
    if not len(points) or near >= camera.useful_range:
        return Views(np.zeros((0, 3)), np.zeros(0), np.zeros(0))
    k = rng.integers(len(points), size=4 * count)
    n = normals[k]
    flat = np.hypot(n[:, 0], n[:, 1]) > 0.3
    heading = np.where(flat, np.degrees(np.arctan2(-n[:, 1], -n[:, 0])) + rng.uniform(-30.0, 30.0, len(k)),
                       rng.uniform(0.0, 360.0, len(k))) % 360.0
    axis = camera_rotations(heading, camera.R_body_cam)[:, :, 2]
    r = rng.uniform(near, camera.useful_range, len(k))
    p = points[k] - r[:, None] * axis
    lo, hi = grid.origin + grid.resolution, grid.upper - grid.resolution
    ok: NDArray[np.bool_] = np.asarray(((p > lo) & (p < hi)).all(axis=1))
    ok[ok] = grid.state(p[ok]) == FREE
    ok[ok] = is_safe_view(safety, p[ok], safe_distance)
    keep = np.flatnonzero(ok)[:count]
    return Views(p[keep], heading[keep], np.zeros(len(keep)))


def reconstruct_utility(u: ArrayLike, gain: ArrayLike, weight: float, scale: float = 1.0) -> Array:
    """The `reconstruct` goal's utility: (1 − weight)·u + weight·gain / max(max(gain), scale), `u` the seed's
    utility of each view and `gain` its `stereo_gain`. `scale` (voxels) keeps a few stray voxels from counting as
    much as a whole face: with the gain normalised by its maximum alone, a view that adds 3 voxels would score
    as the best of views that add 300, and the planner would dither over what is left instead of mapping more.

    >>> reconstruct_utility([0.5, 0.4], [0, 30], 0.6).round(3).tolist()
    [0.2, 0.76]
    >>> reconstruct_utility([0.5, 0.4], [0, 3], 0.6, scale=30.0).round(3).tolist()
    [0.2, 0.22]
    """
    uu = np.asarray(u, dtype=float)
    g = np.asarray(gain, dtype=float)
    top = max(float(g.max()) if len(g) else 0.0, scale)
    norm = g / top if top > 0 else np.zeros(len(g))
    return np.asarray((1.0 - weight) * uu + weight * norm)


@dataclass
class StereoCoverage:
    """The per-voxel record of which occupied voxels of the map the camera has seen well, over the camera poses
    added so far (`add_pose`); `update` checks the voxels not yet seen well against the poses added since the
    last update, and voxels it has not checked before against every pose."""

    camera: Camera
    shape: tuple[int, int, int]
    positions: list[Array] = field(default_factory=list)
    rotations: list[Array] = field(default_factory=list)
    well: NDArray[np.bool_] = field(init=False)
    checked: NDArray[np.bool_] = field(init=False)
    done: int = 0

    def __post_init__(self) -> None:
        self.well = np.zeros(self.shape, dtype=bool)
        self.checked = np.zeros(self.shape, dtype=bool)

    def add_pose(self, position: ArrayLike, R_world_cam: ArrayLike) -> None:
        self.positions.append(np.asarray(position, dtype=float).reshape(3))
        self.rotations.append(np.asarray(R_world_cam, dtype=float).reshape(3, 3))

    def update(self, grid: StateGrid, ids: NDArray[np.int64]) -> float:
        """Bring the record up to date for the voxels `ids` (flat ids into `grid`); the share of them seen well."""
        if not len(ids):
            self.done = len(self.positions)
            return 0.0
        flat_well, flat_checked = self.well.reshape(-1), self.checked.reshape(-1)
        todo = ids[~flat_well[ids]]
        fresh = ~flat_checked[todo]
        ijk = np.stack(np.unravel_index(todo, self.shape), axis=1)
        points = grid.centres(ijk)
        normals = surface_normals(grid.states, ijk)
        seen = np.zeros(len(todo), dtype=bool)
        for k, (p, R) in enumerate(zip(self.positions, self.rotations, strict=True)):
            ask = ~seen & (fresh | (k >= self.done))
            if ask.any():
                seen[ask] = seen_from(points[ask], normals[ask], p, R, self.camera, grid)
        flat_well[todo[seen]] = True
        flat_checked[ids] = True
        self.done = len(self.positions)
        return float(flat_well[ids].mean())

    def share(self, ids: NDArray[np.int64]) -> float:
        """The share of the voxels `ids` seen well (as of the last `update`)."""
        return float(self.well.reshape(-1)[ids].mean()) if len(ids) else 0.0
