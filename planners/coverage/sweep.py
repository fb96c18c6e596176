"""Survey lines of one direction over the free area (seed 002 §2.1: meander passes at the line spacing).

The free area (survey area minus the no-go zones grown by the standoff) is cut into bands one spacing wide across
the line direction; every connected slice of a band gets a line along the band's middle, long enough that the
swath covers the whole slice (its ends may leave the survey area, never enter a grown zone). Slices of adjacent
bands that share a boundary are linked: the links are the connectivity the cell decomposition works on.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely
from numpy.typing import NDArray
from shapely.geometry import LineString, Point
from shapely.geometry.base import BaseGeometry

from .frames import from_sweep, geometry_to_sweep, line_angle

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Piece:
    """One survey line in the sweep frame: row index, v of the row, and its extent u0 < u1."""

    row: int
    v: float
    u0: float
    u1: float

    @property
    def length(self) -> float:
        return self.u1 - self.u0


@dataclass(frozen=True)
class Sweep:
    heading_deg: float
    spacing: float                                # the spacing used (≤ the one asked, so rows fit exactly)
    rows: Array
    pieces: tuple[Piece, ...]                      # sorted by row, then u
    links: tuple[tuple[int, int], ...]             # (lower, upper) pieces whose band slices touch
    inset: float = 0.0                             # how far the outermost bands reach beyond their spacing-wide
                                                   # share (their lines' swaths cover it)

    def points(self, u: Array, v: Array) -> Array:
        """(x, y) of sweep-frame points."""
        return from_sweep(np.stack([np.asarray(u, dtype=float), np.asarray(v, dtype=float)], axis=-1),
                          self.heading_deg)

    def angle(self, direction: int) -> float:
        """Math angle in (x, y) of travel along +u (direction 1) or −u (direction −1)."""
        a = line_angle(self.heading_deg)
        return a if direction > 0 else a + math.pi


def _intervals(geom: BaseGeometry) -> list[tuple[float, float]]:
    out = []
    for part in shapely.get_parts(geom):
        if part.geom_type == "LineString" and not part.is_empty:
            xs = np.asarray(part.coords)[:, 0]
            out.append((float(xs.min()), float(xs.max())))
    return out


def build_sweep(region: BaseGeometry, forbidden: BaseGeometry, heading_deg: float, spacing: float,
                inset: float = 0.0) -> Sweep:
    """Survey lines of `heading_deg` covering `region` (x, y), clipped by `forbidden`, at most `spacing` apart.

    With `inset`, the bands are laid over the region less `inset` at either side across the lines, and the
    outermost bands reach over that margin too: a swath wider than the spacing by 2·`inset` still covers it, and
    fewer lines may fit.

    >>> from shapely.geometry import box
    >>> zone = box(150, 30, 250, 70)
    >>> sweep = build_sweep(box(0, 0, 400, 100).difference(zone), zone, 90.0, 30.0)   # lines run east
    >>> round(sweep.spacing, 2), [(p.row, round(p.u0), round(p.u1)) for p in sweep.pieces]
    (25.0, [(0, 0, 400), (1, 0, 150), (1, 250, 400), (2, 0, 150), (2, 250, 400), (3, 0, 400)])
    >>> sweep.links                                   # which lines of adjacent rows touch
    ((0, 1), (0, 2), (1, 3), (2, 4), (3, 5), (4, 5))
    """
    reg = geometry_to_sweep(region, heading_deg)
    forb = geometry_to_sweep(forbidden, heading_deg)
    shapely.prepare(forb)
    if reg.is_empty:
        return Sweep(heading_deg, spacing, np.zeros(0), (), ())
    umin, vmin, umax, vmax = reg.bounds
    inset = inset if vmax - vmin > 2.0 * inset + 1e-9 else 0.0
    height = vmax - vmin - 2.0 * inset
    n = max(1, math.ceil(height / spacing - 1e-9))
    step = height / n if height > 0 else spacing
    edges = vmin + inset + step * np.arange(n + 1)
    edges[-1] = vmax - inset
    rows = 0.5 * (edges[:-1] + edges[1:])
    lower, upper = edges[:-1].copy(), edges[1:].copy()
    lower[0], upper[-1] = vmin, vmax
    slices = shapely.intersection(reg, shapely.box(umin - 1.0, lower, umax + 1.0, upper))
    min_area = 1e-3 * step * step
    comps: list[list[BaseGeometry]] = []
    pieces: list[Piece] = []
    piece_comps: list[set[int]] = []
    row_pieces: list[list[int]] = []
    for i in range(n):
        polys = [g for g in shapely.get_parts(slices[i]) if g.geom_type == "Polygon" and g.area > min_area]
        comps.append(polys)
        v = float(rows[i])
        found: list[tuple[float, float, set[int]]] = []
        for c, g in enumerate(polys):
            a, _, b, _ = g.bounds
            seg = LineString([(a, v), (b, v)])
            if forb.is_empty or not forb.intersects(seg):
                spans = [(a, b)]
            else:
                spans = [s for s in _intervals(seg.difference(forb)) if s[1] - s[0] > 1e-3]
            found.extend((s0, s1, {c}) for s0, s1 in spans)
        found.sort(key=lambda s: s[0])
        merged: list[tuple[float, float, set[int]]] = []
        for s0, s1, cs in found:
            if merged and s0 <= merged[-1][1] + 1e-6:
                m0, m1, mc = merged[-1]
                merged[-1] = (m0, max(m1, s1), mc | cs)
            else:
                merged.append((s0, s1, cs))
        ids = []
        for s0, s1, cs in merged:
            ids.append(len(pieces))
            pieces.append(Piece(i, v, s0, s1))
            piece_comps.append(cs)
        row_pieces.append(ids)
    # slices of adjacent bands touch along the free intervals of their common boundary
    links: list[tuple[int, int]] = []
    if n > 1:
        bounds = shapely.intersection(reg, shapely.linestrings(
            np.stack([np.stack([np.full(n - 1, umin - 1.0), edges[1:-1]], axis=1),
                      np.stack([np.full(n - 1, umax + 1.0), edges[1:-1]], axis=1)], axis=1)))
        eps = 1e-4 * step
        for i in range(n - 1):
            if not comps[i] or not comps[i + 1]:
                continue
            touching: set[tuple[int, int]] = set()
            below = np.array(comps[i], dtype=object)
            above = np.array(comps[i + 1], dtype=object)
            b = float(edges[i + 1])
            for lo, hi in _intervals(bounds[i]):
                if hi - lo <= 1e-6:
                    continue
                mid = 0.5 * (lo + hi)
                xs = np.flatnonzero(shapely.intersects(below, Point(mid, b - eps)))
                ys = np.flatnonzero(shapely.intersects(above, Point(mid, b + eps)))
                touching.update((int(x), int(y)) for x in xs for y in ys)
            for p in row_pieces[i]:
                for q in row_pieces[i + 1]:
                    if min(pieces[p].u1, pieces[q].u1) < max(pieces[p].u0, pieces[q].u0) - 1e-9:
                        continue
                    if any((x, y) in touching for x in piece_comps[p] for y in piece_comps[q]):
                        links.append((p, q))
    return Sweep(heading_deg, step, rows, tuple(pieces), tuple(links), inset)


class SweepCache:
    """Sweeps of one scene at one spacing, built once per heading."""

    def __init__(self, region: BaseGeometry, forbidden: BaseGeometry, spacing: float, inset: float = 0.0):
        self.region = region
        self.forbidden = forbidden
        self.spacing = spacing
        self.inset = inset
        self._built: dict[float, Sweep] = {}

    def get(self, heading_deg: float) -> Sweep:
        key = round(float(heading_deg) % 180.0, 9)
        if key not in self._built:
            self._built[key] = build_sweep(self.region, self.forbidden, key, self.spacing, self.inset)
        return self._built[key]
