"""A synthetic scene for next-best-view scanning: boxes and vertical cylinders on a flat seabed, with the 3-D
scanner simulated by exact ray casting (a test double for seed 002 §2.2.2 experiments, like the seed's
breakwater blocks; used by tests and by the `nbv` benchmark for every planner alike).

Coordinates are NED metres (depth grows downwards; a box's `lo` holds its smallest north, east and depth).
`surface_keys` gives the ground truth of coverage: the voxels that contain a point of an object's surface
(faces resting on the seabed or buried in another object excluded).

>>> s = Scene(boxes=(Box((10, -2, 6), (14, 2, 10)),), seabed_depth=10.0)
>>> s.cast(np.zeros(3), np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.8, 0.0, 0.6]]), 30.0).round(3).tolist()
[inf, 10.0, 12.5]
>>> s.distance(np.array([[8.0, 0.0, 8.0], [12.0, 5.0, 4.0]])).round(3).tolist()
[2.0, 3.606]
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from planners.nbv.planner import Scan
from planners.nbv.views import Scanner, View

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Box:
    """An axis-aligned box from `lo` to `hi` (north, east, depth)."""

    lo: tuple[float, float, float]
    hi: tuple[float, float, float]


@dataclass(frozen=True)
class Cylinder:
    """A vertical cylinder: axis at (north, east), radius, from depth `top` down to depth `bottom`."""

    north: float
    east: float
    radius: float
    top: float
    bottom: float


@dataclass(frozen=True)
class Scene:
    boxes: tuple[Box, ...] = ()
    cylinders: tuple[Cylinder, ...] = ()
    seabed_depth: float = math.inf

    def cast(self, origin: ArrayLike, directions: ArrayLike, max_range: float) -> Array:
        """Distance along each unit direction (N, 3) from `origin` to the first surface; inf beyond max_range."""
        o = np.asarray(origin, dtype=float).reshape(3)
        d = np.asarray(directions, dtype=float).reshape(-1, 3)
        t = np.full(len(d), np.inf)
        with np.errstate(divide="ignore", invalid="ignore"):
            if math.isfinite(self.seabed_depth):
                ts = (self.seabed_depth - o[2]) / d[:, 2]
                t = np.where((d[:, 2] > 0) & (ts >= 0), np.minimum(t, ts), t)
            for b in self.boxes:
                t = np.minimum(t, _ray_box(o, d, np.asarray(b.lo, dtype=float), np.asarray(b.hi, dtype=float)))
            for c in self.cylinders:
                t = np.minimum(t, _ray_cylinder(o, d, c))
        return np.where(t <= max_range, t, np.inf)

    def scan(self, view: View, scanner: Scanner) -> Scan:
        """The scanner's frame from a view: endpoints at returns, or at the range for beams without one."""
        dirs = scanner.directions([view.heading_deg], [view.pitch_deg])[0]
        t = self.cast(view.point, dirs, scanner.max_range)
        hit = np.isfinite(t)
        ends = view.point + dirs * np.where(hit, t, scanner.max_range)[:, None]
        return Scan(view.point.copy(), ends, hit)

    def distance(self, points: ArrayLike) -> Array:
        """Distance from points (N, 3) outside the solids to the nearest solid (0 inside one)."""
        p = np.asarray(points, dtype=float).reshape(-1, 3)
        out = np.full(len(p), np.inf)
        if math.isfinite(self.seabed_depth):
            out = np.maximum(self.seabed_depth - p[:, 2], 0.0)
        for b in self.boxes:
            gap = np.maximum(np.maximum(np.asarray(b.lo) - p, p - np.asarray(b.hi)), 0.0)
            out = np.minimum(out, np.linalg.norm(gap, axis=1))
        for c in self.cylinders:
            radial = np.maximum(np.hypot(p[:, 0] - c.north, p[:, 1] - c.east) - c.radius, 0.0)
            vertical = np.maximum(np.maximum(c.top - p[:, 2], p[:, 2] - c.bottom), 0.0)
            out = np.minimum(out, np.hypot(radial, vertical))
        return out

    def surface_points(self, spacing: float) -> Array:
        """Points ≤ `spacing` apart on the objects' visible surfaces (not on the seabed, not inside a solid)."""
        parts = [_box_surface(b, spacing) for b in self.boxes] + [_cylinder_surface(c, spacing)
                                                                   for c in self.cylinders]
        if not parts:
            return np.zeros((0, 3))
        p = np.concatenate(parts)
        keep = p[:, 2] < self.seabed_depth - 1e-6
        for b in self.boxes:
            keep &= ~((p > np.asarray(b.lo) + 1e-6) & (p < np.asarray(b.hi) - 1e-6)).all(axis=1)
        for c in self.cylinders:
            keep &= ~((np.hypot(p[:, 0] - c.north, p[:, 1] - c.east) < c.radius - 1e-6)
                      & (p[:, 2] > c.top + 1e-6) & (p[:, 2] < c.bottom - 1e-6))
        return p[keep]

    def surface_keys(self, resolution: float) -> NDArray[np.int64]:
        """Keys (floor(p / resolution)) of the voxels holding some of the objects' visible surface."""
        pts = self.surface_points(resolution / 3.0)
        return np.unique(np.floor(pts / resolution).astype(np.int64), axis=0)


def survey_scans(scene: Scene, lo: ArrayLike, hi: ArrayLike, depth: float, spacing: float,
                 fov_deg: tuple[float, float] = (120.0, 60.0), max_range: float = 60.0,
                 rays: tuple[int, int] = (96, 48)) -> list[Scan]:
    """Down-looking frames over the (north, east) box [lo, hi] every `spacing` metres at `depth`: the prior an
    area survey (§2.1) leaves before the object is scanned (water column free, tops and seabed occupied)."""
    scanner = Scanner(fov_deg, max_range, rays)
    a, b = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    scans = []
    for n in np.arange(a[0], b[0] + 1e-9, spacing):
        for e in np.arange(a[1], b[1] + 1e-9, spacing):
            scans.append(scene.scan(View.at((n, e, depth), 0.0, -90.0), scanner))
    return scans


def _ray_box(o: Array, d: Array, lo: Array, hi: Array) -> Array:
    inv = 1.0 / d
    t1, t2 = (lo - o) * inv, (hi - o) * inv
    t_near = np.nanmax(np.minimum(t1, t2), axis=1)
    t_far = np.nanmin(np.maximum(t1, t2), axis=1)
    ok = (t_far >= np.maximum(t_near, 0.0))
    return np.where(ok, np.maximum(t_near, 0.0), np.inf)


def _ray_cylinder(o: Array, d: Array, c: Cylinder) -> Array:
    px, py = o[0] - c.north, o[1] - c.east
    a = d[:, 0] ** 2 + d[:, 1] ** 2
    b = 2.0 * (px * d[:, 0] + py * d[:, 1])
    cc = px * px + py * py - c.radius**2
    disc = b * b - 4.0 * a * cc
    t_side = (-b - np.sqrt(np.maximum(disc, 0.0))) / (2.0 * a)
    z = o[2] + t_side * d[:, 2]
    side_ok = (disc >= 0) & (a > 0) & (t_side >= 0) & (z >= c.top) & (z <= c.bottom)
    t = np.where(side_ok, t_side, np.inf)
    for depth in (c.top, c.bottom):
        tc = (depth - o[2]) / d[:, 2]
        x, y = px + tc * d[:, 0], py + tc * d[:, 1]
        cap_ok = (tc >= 0) & (x * x + y * y <= c.radius**2)
        t = np.where(cap_ok, np.minimum(t, tc), t)
    return t


def _grid(a0: float, a1: float, spacing: float) -> Array:
    return np.linspace(a0, a1, max(2, math.ceil((a1 - a0) / spacing) + 1))


def _box_surface(b: Box, spacing: float) -> Array:
    lo, hi = np.asarray(b.lo, dtype=float), np.asarray(b.hi, dtype=float)
    out = []
    for axis in range(3):
        u, v = [a for a in range(3) if a != axis]
        uu, vv = np.meshgrid(_grid(lo[u], hi[u], spacing), _grid(lo[v], hi[v], spacing), indexing="ij")
        for value in (lo[axis], hi[axis]):
            face = np.zeros((uu.size, 3))
            face[:, axis], face[:, u], face[:, v] = value, uu.ravel(), vv.ravel()
            out.append(face)
    return np.concatenate(out)


def _cylinder_surface(c: Cylinder, spacing: float) -> Array:
    angles = np.linspace(0.0, 2.0 * math.pi, max(8, math.ceil(2.0 * math.pi * c.radius / spacing)), endpoint=False)
    depths = _grid(c.top, c.bottom, spacing)
    aa, dd = np.meshgrid(angles, depths, indexing="ij")
    side = np.stack([c.north + c.radius * np.cos(aa.ravel()), c.east + c.radius * np.sin(aa.ravel()), dd.ravel()],
                    axis=1)
    caps = []
    for r in _grid(0.0, c.radius, spacing):
        n = max(1, math.ceil(2.0 * math.pi * r / spacing))
        a = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
        ring = np.stack([c.north + r * np.cos(a), c.east + r * np.sin(a), np.zeros(n)], axis=1)
        for depth in (c.top, c.bottom):
            caps.append(ring + [0.0, 0.0, depth])
    return np.concatenate([side, *caps])
