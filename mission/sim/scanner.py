"""The simulated 3-D scanner (laser or structured light) of seed 002 §2.2.2: a frustum of rays cast against the
world.

Mounting. The scanner looks forward from the vehicle origin, tilted down by `tilt_deg` about the body y axis;
its rays form the same pinhole grid (equal steps of tan(angle)) across the field of view `fov_deg = (horizontal,
vertical)` as `planners.nbv.Scanner` uses to model views: a ray's body direction is the planner's body ray
pitched by −`tilt_deg`, so a view planned with heading h and pitch −`tilt_deg` is exactly what the vehicle sees
when it holds heading h (the vehicle itself keeps zero pitch and roll). The vehicle's heading turns the frustum
into the world (`mission.frames.rotation_zyx`). All rays of a frame are cast in one `mujoco.mj_multiRay` call
against the scene's MuJoCo model (`mission.sim.mjworld`), like the multibeam (`mission.sim.mbes`).

Speed. MuJoCo's ray test against a height field costs with the field's size, and a scanner's rays run nearly
level over the seabed: against the whole reference world (500 × 600 cells) a frame of 1,728 rays took ~50 ms.
`LocalWorld` casts instead against the same scene with its seabed cropped to a square around the vehicle (the
same grid nodes, so the same surface; rebuilt in milliseconds when the vehicle moves on): ~5 ms.

Each return's range gets Gaussian noise of `range_sigma` (about a centimetre for a laser or structured-light
scanner at ten metres). A ray with nothing within `max_range` is a no-return: `hit` False, range NaN.

>>> import numpy as np
>>> d = frustum_directions((90.0, 60.0), (3, 3), tilt_deg=0.0)
>>> d[4].round(6).tolist(), d[5].round(3).tolist()        # centre ray forward; right edge 45° to starboard
([1.0, 0.0, 0.0], [0.707, 0.707, 0.0])
>>> frustum_directions((90.0, 60.0), (1, 1), tilt_deg=30.0)[0].round(3).tolist()   # tilted 30° down
[0.866, 0.0, 0.5]
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mission.frames import Array, rotation_zyx
from mission.language.models import Scanner as ScannerSettings
from mission.sim.mjworld import MjWorld
from mission.world.scene import Scene
from mission.world.terrain import HeightField
from planners.nbv import Scanner as ViewModel

DEFAULT_RAYS = (48, 36)
"""Rays across and up the frustum: 1.25° apart, 22 cm at 10 m."""
DEFAULT_TILT_DEG = 25.0
"""Downward tilt of the mounting: the frustum spans 2.5° to 47.5° below the horizon, right for views from above
the safety distance onto an object on the seabed."""


def frustum_directions(fov_deg: tuple[float, float], rays: tuple[int, int], tilt_deg: float) -> Array:
    """Unit ray directions (R, 3) in the body frame (x forward, y starboard, z down) of a scanner tilted down by
    `tilt_deg`: `planners.nbv.Scanner`'s rays at pitch −tilt, so planning and sensing share one geometry."""
    model = ViewModel(fov_deg, 1.0, rays)
    return np.asarray(model.directions(np.array([0.0]), np.array([-tilt_deg]))[0], dtype=float)


@dataclass(frozen=True, eq=False)
class ScanHits:
    """One frame in the world NED frame (true geometry): arrays have one row per ray and are read-only."""

    ranges: Array
    """(R,) measured range (m) with noise; NaN for a no-return."""
    hit: NDArray[np.bool_]
    directions_body: Array
    """(R, 3) ray directions in the body frame."""
    origin_ned: Array
    true_points_ned: Array
    """(R, 3) the exact surface point each ray hit (NaN for a no-return): what the sensor truly saw."""
    object_ids: NDArray[np.str_]
    """(R,) the object a ray hit ("" for the seabed or a no-return)."""


class LocalWorld:
    """MuJoCo models of a scene whose seabed is cropped to a square of half-side `half` metres around a point;
    `around(north, east)` returns one whose crop holds every point within `reach` of (north, east)."""

    def __init__(self, scene: Scene, reach: float, half: float = 40.0) -> None:
        if half <= reach:
            raise ValueError(f"the crop's half-side ({half} m) must exceed the reach ({reach} m)")
        self.scene, self.reach, self.half = scene, float(reach), float(half)
        self.centre = (math.inf, math.inf)
        self.world: MjWorld | None = None

    def around(self, north: float, east: float) -> MjWorld:
        margin = self.half - self.reach - 2.0
        if self.world is None or max(abs(north - self.centre[0]), abs(east - self.centre[1])) > margin:
            self.world = MjWorld(dataclasses.replace(self.scene, seabed=crop(self.scene.seabed, north, east,
                                                                             self.half)))
            self.centre = (north, east)
        return self.world


def crop(field: HeightField, north: float, east: float, half: float) -> HeightField:
    """The part of a height field within `half` metres (plus a node) of (north, east), on the same nodes."""
    r = field.resolution
    i0 = max(int(math.floor((north - half - field.north0) / r)), 0)
    i1 = min(int(math.ceil((north + half - field.north0) / r)) + 1, field.depth.shape[0])
    j0 = max(int(math.floor((east - half - field.east0) / r)), 0)
    j1 = min(int(math.ceil((east + half - field.east0) / r)) + 1, field.depth.shape[1])
    return HeightField(field.depth[i0:i1, j0:j1], field.north0 + i0 * r, field.east0 + j0 * r, r)


class Scanner3D:
    """A frustum scanner at the vehicle origin, tilted down by `tilt_deg` (see the module docstring); `world` is
    one MuJoCo model, or a `LocalWorld` that follows the vehicle."""

    def __init__(self, world: MjWorld | LocalWorld, fov_deg: tuple[float, float] = (60.0, 45.0),
                 max_range: float = 12.0, rate_hz: float = 2.0, rays: tuple[int, int] = DEFAULT_RAYS,
                 tilt_deg: float = DEFAULT_TILT_DEG, range_sigma: float = 0.01, seed: int = 0) -> None:
        if not (max_range > 0.0 and math.isfinite(max_range)):
            raise ValueError(f"scanner max_range must be a positive number of metres, got {max_range}")
        if rate_hz <= 0.0:
            raise ValueError(f"scanner rate_hz must be > 0, got {rate_hz}")
        if range_sigma < 0.0:
            raise ValueError(f"scanner range_sigma must be >= 0, got {range_sigma}")
        self.world = world
        self.fov_deg = (float(fov_deg[0]), float(fov_deg[1]))
        self.max_range = float(max_range)
        self.rate_hz = float(rate_hz)
        self.rays = (int(rays[0]), int(rays[1]))
        self.tilt_deg = float(tilt_deg)
        self.range_sigma = float(range_sigma)
        self.rng = np.random.default_rng(seed)
        self.directions_body: Array = frustum_directions(self.fov_deg, self.rays, self.tilt_deg)
        self.directions_body.setflags(write=False)

    @classmethod
    def from_settings(cls, scene: Scene, settings: ScannerSettings, seed: int = 0) -> Scanner3D:
        """A scanner in `scene` configured by a mission's `sensors.scanner` block (rays and tilt: the defaults
        here)."""
        fov = (float(settings.fov_deg[0]), float(settings.fov_deg[1]))
        return cls(LocalWorld(scene, settings.max_range), fov, settings.max_range, settings.rate_hz, seed=seed)

    @property
    def period_s(self) -> float:
        return 1.0 / self.rate_hz

    def scan(self, north: float, east: float, depth: float, heading_deg: float, pitch_deg: float = 0.0,
             roll_deg: float = 0.0) -> ScanHits:
        """Cast the frustum from the vehicle pose and return the noisy frame."""
        origin = np.array([north, east, depth], dtype=float)
        dirs = self.directions_body @ rotation_zyx(heading_deg, pitch_deg, roll_deg).T
        world = self.world.around(north, east) if isinstance(self.world, LocalWorld) else self.world
        dist, geomid = world.cast_fan(origin, dirs, self.max_range)
        hit = (geomid >= 0) & (dist <= self.max_range)
        exact = np.where(hit, dist, np.nan)
        ranges = exact.copy()
        if self.range_sigma > 0.0:
            ranges = np.maximum(ranges + self.rng.normal(0.0, self.range_sigma, len(ranges)), 0.0)
        true_points = origin + dirs * exact[:, None]
        object_ids = world.objects_hit(np.where(hit, geomid, -1))
        for arr in (ranges, hit, origin, true_points, object_ids):
            arr.setflags(write=False)
        return ScanHits(ranges, hit, self.directions_body, origin, true_points, object_ids)
