"""The geometry of one coverage request (seed 002 §2.1: the survey area, the forbidden zones, the vehicle's
turning radius), built once and shared by every line direction tried.

Distances kept from a no-go zone: no part of the path comes closer than half the `clearance` (`hard`); survey
lines end, contour passes run and transits route at the standoff R + clearance (`forbidden`), which leaves room
for a turn of radius R after a line's end.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray
from shapely.geometry import Polygon
from shapely.geometry.base import BaseGeometry

from .frames import polygon_ne
from .routes import Router
from .turns import dubins, dubins_path

Array = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
QUAD = 4                          # buffer resolution: segments per quarter circle


@dataclass
class Scene:
    area: Polygon
    zones: BaseGeometry           # union of the no-go zones (possibly empty)
    free: BaseGeometry            # area minus zones: what must be covered
    radius: float
    clearance: float
    swath: float
    standoff: float
    forbidden: BaseGeometry       # zones grown by the standoff
    region: BaseGeometry          # area minus forbidden: where survey lines are laid
    hard: BaseGeometry            # zones grown by half the clearance: the path never touches it
    router: Router

    @classmethod
    def build(
        cls,
        area: ArrayLike,
        exclude: Sequence[ArrayLike],
        radius: float,
        clearance: float,
        swath: float,
    ) -> Scene:
        if radius < 0.0 or not math.isfinite(radius):
            raise ValueError(f"turn radius must be non-negative, got {radius}")
        if clearance <= 0.0:
            raise ValueError(f"clearance must be positive, got {clearance}")
        if swath <= 0.0:
            raise ValueError(f"swath must be positive, got {swath}")
        poly = polygon_ne(area, "the survey area")
        zone_polys = [polygon_ne(z, f"no-go zone {k + 1}") for k, z in enumerate(exclude)]
        zones = shapely.union_all(zone_polys) if zone_polys else Polygon()
        free = poly.difference(zones)
        if free.area <= 0.0:
            raise ValueError("the no-go zones cover the whole survey area")
        standoff = radius + clearance
        if zones.is_empty:
            forbidden: BaseGeometry = Polygon()
            hard: BaseGeometry = Polygon()
            blocking: BaseGeometry = Polygon()
        else:
            forbidden = zones.buffer(standoff, quad_segs=QUAD)
            hard = zones.buffer(0.5 * clearance, quad_segs=QUAD)
            # chords of the grown zones' round corners sag inwards; visibility is tested against a slightly
            # smaller zone so that a route may run along the grown boundary
            inner = standoff * math.cos(math.pi / (4 * QUAD)) ** 2 - 1e-3
            blocking = zones.buffer(max(inner, 0.6 * clearance), quad_segs=QUAD)
        region = poly.difference(forbidden)
        shapely.prepare(hard)
        # route corners: the zones grown by the standoff with mitred corners (one node per corner)
        corners = zones.buffer(standoff, join_style="mitre", mitre_limit=2.0) if not zones.is_empty else Polygon()
        return cls(poly, zones, free, float(radius), float(clearance), float(swath), standoff, forbidden,
                   region, hard, Router(corners, blocking))

    @property
    def has_zones(self) -> bool:
        return not self.zones.is_empty

    def valid(self, paths: Sequence[Array]) -> BoolArray:
        """Whether each polyline keeps out of the zones (by half the clearance)."""
        if not self.has_zones or not paths:
            return np.ones(len(paths), dtype=bool)
        lines = shapely.linestrings(np.concatenate(paths), indices=np.repeat(np.arange(len(paths)),
                                                                           [len(p) for p in paths]))
        return ~np.asarray(shapely.intersects(lines, self.hard), dtype=bool)

    def transit(self, p: Array, angle_p: float, q: Array, angle_q: float) -> Array:
        """A flyable path from pose (p, angle_p) to pose (q, angle_q) that keeps out of the zones.

        The Dubins path when it is clear; otherwise the shortest route around the zones, flown from corner to corner
        by Dubins pieces, each reaching the farthest corner it can without touching a zone (where none clears,
        the straight chord to the next corner, which is clear).
        """
        path = dubins_path(p, angle_p, q, angle_q, self.radius)
        if not self.has_zones or bool(self.valid([path])[0]):
            return path
        route = self.router.route(p, q)
        if len(route) == 2:
            return route
        angles = [angle_p]
        for k in range(1, len(route) - 1):
            d = route[k + 1] - route[k - 1]
            angles.append(math.atan2(d[1], d[0]))
        angles.append(angle_q)
        out = [route[:1]]
        i = 0
        while i < len(route) - 1:                  # from each corner, the farthest one a clear Dubins path reaches
            later = list(range(len(route) - 1, i, -1))
            pieces = [dubins_path(route[i], angles[i], route[j], angles[j], self.radius) for j in later]
            ok = self.valid(pieces)
            k = int(np.argmax(ok)) if ok.any() else len(later) - 1
            out.append(pieces[k][1:] if ok[k] else route[later[k] : later[k] + 1])
            i = later[k]
        return np.concatenate(out)

    def transit_costs(self, p: Array, angle_p: Array, q: Array, angle_q: Array) -> Array:
        """Approximate lengths of the transits from each pose p[i] to each pose q[j]: Dubins where the straight
        way is clear, the route around the zones (plus the Dubins excess over the straight) otherwise."""
        n, m = len(p), len(q)
        if n == 0 or m == 0:
            return np.zeros((n, m))
        length, _, _ = dubins(np.repeat(p, m, axis=0), np.repeat(angle_p, m), np.tile(q, (n, 1)),
                              np.tile(angle_q, n), self.radius)
        length = length.reshape(n, m)
        if not self.has_zones:
            return length
        routed = self.router.lengths(p, q)
        direct = np.linalg.norm(p[:, None, :] - q[None, :, :], axis=2)
        return _penalise_unrouted(np.where(routed <= direct + 1e-9, length, routed + (length - direct)), length)

    def pair_costs(self, p: Array, angle_p: Array, q: Array, angle_q: Array) -> Array:
        """`transit_costs` for the pairs (p[i], q[i])."""
        if len(p) == 0:
            return np.zeros(0)
        length, _, _ = dubins(p, angle_p, q, angle_q, self.radius)
        if not self.has_zones:
            return length
        routed = self.router.pair_lengths(p, q)
        direct = np.linalg.norm(p - q, axis=1)
        return _penalise_unrouted(np.where(routed <= direct + 1e-9, length, routed + (length - direct)), length)


def _penalise_unrouted(cost: Array, length: Array) -> Array:
    """Where no route round the zones exists (a point shut in by zones), a large finite cost keeps orderings
    well defined; the transit itself then falls back to the straight way."""
    return np.where(np.isfinite(cost), cost, 10.0 * length + 1e6)
