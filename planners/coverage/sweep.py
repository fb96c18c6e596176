"""Survey lines of one direction over the free area (seed 002 §2.1: meander passes at the line spacing).

The free area (survey area minus the no-go zones grown by the standoff) is cut into bands one spacing wide across
the line direction; every connected slice of a band gets a line along the band's middle, long enough that the
swath covers the whole slice (its ends may leave the survey area, never enter a grown zone). Slices of adjacent
bands that share a boundary are linked: the links are the connectivity the cell decomposition works on.

A line need only stop short of a zone (by the turning radius plus the clearance) where it turns; where it merely
passes a zone, the clearance is enough. So our lines may run on past a zone they do not cross by the clearance,
slide sideways within what the swath's overlap spares to clear one, or bend round a small one on Dubins ramps
(`Passing`): no cell splits there, and their swaths cover the strips beside the zone that contour passes would.
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
from .turns import dubins_path

Array = NDArray[np.float64]


Detour = tuple[tuple[float, float], ...]      # sweep-frame points from (u_in, v) to (u_out, v), u increasing


@dataclass(frozen=True)
class Piece:
    """One survey line in the sweep frame: row index, v of the line, its extent u0 < u1, and the detours by which
    it bends round small zones on the way (see `_bypassed`)."""

    row: int
    v: float
    u0: float
    u1: float
    detours: tuple[Detour, ...] = ()

    @property
    def length(self) -> float:
        return self.u1 - self.u0

    def room(self, direction: int) -> float:
        """How far the end the line is flown towards (`direction` ±1 along u) may be pulled back before a detour."""
        if not self.detours:
            return self.length
        return self.u1 - self.detours[-1][-1][0] if direction > 0 else self.detours[0][0][0] - self.u0

    def uv(self, u_start: float, u_end: float) -> Array:
        """(K, 2) sweep-frame points of the line flown from u_start to u_end (either way), detours included."""
        pts = [(u_start, self.v)]
        for d in self.detours:
            pts.extend(d)
        pts.append((u_end, self.v))
        out = np.array(pts if u_start <= u_end else [pts[0], *reversed(pts[1:-1]), pts[-1]], dtype=float)
        keep = np.ones(len(out), dtype=bool)
        keep[1:] = np.linalg.norm(np.diff(out, axis=0), axis=1) > 1e-9
        return out[keep]

    def cut(self, lo: float, hi: float) -> Piece:
        """The line cut to [lo, hi], widened to take in whole any detour it reaches into."""
        keep = tuple(d for d in self.detours if d[-1][0] > lo and d[0][0] < hi)
        if keep:
            lo, hi = min(lo, keep[0][0][0]), max(hi, keep[-1][-1][0])
        return Piece(self.row, self.v, lo, hi, keep)


@dataclass(frozen=True)
class Sweep:
    heading_deg: float
    spacing: float                                # the spacing used (≤ the one asked, so rows fit exactly)
    rows: Array
    pieces: tuple[Piece, ...]                      # sorted by row, then u
    links: tuple[tuple[int, int], ...]             # (lower, upper) pieces whose band slices touch
    reach: tuple[float, float] = (0.0, 0.0)        # how far the first band reaches below, and the last above,
                                                   # their spacing-wide share (their lines' swaths cover it; < 0
                                                   # where the share overhangs the region)

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


def _passes(forb: BaseGeometry, block: BaseGeometry | None, v: float, u0: float, u1: float) -> bool:
    """Whether row `v` (sweep frame) may run on from u0 to u1: the gap lies in `forb` and misses `block`.

    >>> from shapely.geometry import box
    >>> forb = box(10.0, -20.0, 40.0, 20.0)
    >>> [_passes(forb, box(20.0, y, 30.0, y + 10.0), 0.0, 10.0, 40.0) for y in (-5.0, 5.0)]
    [False, True]
    """
    if block is None:
        return False
    gap = LineString([(u0, v), (u1, v)])
    return gap.difference(forb).length < 1e-6 and not block.intersects(gap)


Span = tuple[float, float, set[int]]          # u0, u1 of a line and the band slices it covers
BEND = math.radians(10.0)                     # steepest slant of a detour's ramps (steeper ones leave wider wedges
                                              # between their passes' flat-capped swaths uncovered)
CLEAR = 0.05                                  # how far a moved line passes clear of what blocked it (m)


@dataclass(frozen=True)
class Passing:
    """How lines may pass the zones instead of stopping short of them: without crossing `blocking` (the zones grown
    by the clearance), moved sideways by up to `shift`, or bent round a zone by up to `reach` on turns of
    `radius`."""

    blocking: BaseGeometry
    shift: float = 0.0
    reach: float = 0.0
    radius: float = 0.0


def _row_spans(polys: list[BaseGeometry], forb: BaseGeometry, block: BaseGeometry | None, v: float) -> list[Span]:
    """The lines of row `v` over the band slices `polys`: each slice's extent less `forb`, joined where they touch
    or (see `_passes`) may run on past a zone."""
    found: list[Span] = []
    for c, g in enumerate(polys):
        a, _, b, _ = g.bounds
        seg = LineString([(a, v), (b, v)])
        if forb.is_empty or not forb.intersects(seg):
            spans = [(a, b)]
        else:
            spans = [s for s in _intervals(seg.difference(forb)) if s[1] - s[0] > 1e-3]
        found.extend((s0, s1, {c}) for s0, s1 in spans)
    found.sort(key=lambda s: s[0])
    merged: list[Span] = []
    for s0, s1, cs in found:
        if merged and (s0 <= merged[-1][1] + 1e-6 or _passes(forb, block, v, merged[-1][1], s0)):
            m0, m1, mc = merged[-1]
            merged[-1] = (m0, max(m1, s1), mc | cs)
        else:
            merged.append((s0, s1, cs))
    return merged


def _shifted(polys: list[BaseGeometry], forb: BaseGeometry, block: BaseGeometry, v: float, lo: float, hi: float,
             spans: list[Span]) -> tuple[float, list[Span]]:
    """Row `v` moved sideways by an offset in [lo, hi] where that lets it run past a zone in fewer lines (the
    least offset that gives the fewest): a line that clips a zone's edge slides clear of it, and no cell splits
    there. The offset is small enough that the line's swath still covers its whole band. Tried: just clear of the
    top or the bottom of what blocks each gap within reach."""
    tries: set[float] = set()
    for (_, a, _), (b, _, _) in zip(spans[:-1], spans[1:], strict=True):
        near = block.intersection(shapely.box(a, v + lo - CLEAR, b, v + hi + CLEAR))
        if near.is_empty:
            continue
        _, bottom, _, top = near.bounds
        tries.update(d for d in (top + CLEAR - v, bottom - CLEAR - v) if lo <= d <= hi)
    best = (len(spans), 0.0, v, spans)
    for d in sorted(tries, key=abs):
        moved = _row_spans(polys, forb, block, v + d)
        if moved and (len(moved), abs(d)) < best[:2]:
            best = (len(moved), abs(d), v + d, moved)
    return best[2], best[3]


def detour(u_in: float, u_out: float, v: float, dv: float, radius: float) -> Detour:
    """A line at `v` bent sideways by `dv` between u_in and u_out: a ramp of two Dubins arcs of `radius` and a
    slant of at most `BEND` each way, and the stretch in between flown straight at v + dv.

    >>> pts = np.array(detour(0.0, 100.0, 0.0, 10.0, 6.0))
    >>> pts[0].tolist(), pts[-1].round(9).tolist(), round(float(pts[:, 1].max()), 9)
    ([0.0, 0.0], [100.0, 0.0], 10.0)
    """
    ramp = _ramp(abs(dv), radius)
    a = np.array([u_in, v])
    b = np.array([u_in + ramp, v + dv])
    c = np.array([u_out - ramp, v + dv])
    d = np.array([u_out, v])
    up = dubins_path(a, 0.0, b, 0.0, radius)
    down = dubins_path(c, 0.0, d, 0.0, radius)
    return tuple((float(x), float(y)) for x, y in np.concatenate([up, down]))


def _ramp(dv: float, radius: float) -> float:
    """Length along the line of a sideways step of `dv`: two arcs of `radius`, slanting at most `BEND` between.

    >>> round(_ramp(0.0, 6.0), 9), round(_ramp(10.0, 6.0), 3)
    (0.0, 57.763)
    """
    if radius <= 0.0:
        return dv / math.tan(BEND)
    arcs = 2.0 * radius * (1.0 - math.cos(BEND))
    if dv <= arcs:
        return 2.0 * radius * math.sin(math.acos(1.0 - dv / (2.0 * radius)))
    return 2.0 * radius * math.sin(BEND) + (dv - arcs) / math.tan(BEND)


Bent = tuple[Span, tuple[Detour, ...]]        # a line and its detours


def _bypassed(spans: list[Span], forb: BaseGeometry, passing: Passing, v: float) -> list[Bent]:
    """Consecutive lines of row `v` joined by a detour round the zone between them, where one within `reach` clears
    it: bending round a small zone costs a few metres, stopping short of it a cell split and contour passes. A
    detour runs from the ramp before the nearest extent of what blocks the row to the ramp after it, on the side
    needing the smaller step, and must keep out of `blocking` all the way."""
    out: list[Bent] = [(spans[0], ())]
    for span in spans[1:]:
        (a0, a, cs), bends = out[-1]
        b, b1, ds = span
        found = _detour(forb, passing, v, a0, a, b, b1)
        if found is None:
            out.append((span, ()))
        else:
            out[-1] = ((a0, b1, cs | ds), (*bends, found))
    return out


def _detour(forb: BaseGeometry, passing: Passing, v: float, a0: float, a: float, b: float,
            b1: float) -> Detour | None:
    """The detour of row `v` past the zone in the gap (a, b) between lines from a0 and to b1, or None."""
    gap = LineString([(a, v), (b, v)])
    if gap.difference(forb).length > 1e-6:                 # a bay of the area, not a zone, splits the row
        return None
    reach = passing.reach
    near = passing.blocking.intersection(shapely.box(a, v - reach - 1.0, b, v + reach + 1.0))
    if near.is_empty:
        return None
    nu0, nv0, nu1, nv1 = near.bounds
    steps = [d for d, edge in ((nv1 + CLEAR - v, nv1 < v + reach), (nv0 - CLEAR - v, nv0 > v - reach)) if edge]
    for dv in sorted(steps, key=abs):
        ramp = _ramp(abs(dv), passing.radius)
        u_in, u_out = nu0 - ramp, nu1 + ramp
        if u_in < a0 or u_out > b1:
            continue
        path = detour(u_in, u_out, v, dv, passing.radius)
        if not passing.blocking.intersects(LineString(path)):
            return path
    return None


def build_sweep(region: BaseGeometry, forbidden: BaseGeometry, heading_deg: float, spacing: float,
                inset: float = 0.0, passing: Passing | None = None, phase: float | None = None) -> Sweep:
    """Survey lines of `heading_deg` covering `region` (x, y), clipped by `forbidden`, at most `spacing` apart.

    With `passing` (see `Passing`), a line is cut only where it would cross `passing.blocking` (inside
    `forbidden`): one that merely grazes `forbidden` runs on past the zone (no turn is needed there, so it need not
    keep the turning room), and its swath covers the strip beside the zone that a cut line would leave to contour
    passes. A row that a zone splits may then be moved sideways by up to `passing.shift` (at most what the swath's
    overlap leaves over the band, so the band stays covered) where that lets it run past the zone (`Piece.v` is
    then off the row's middle, `Sweep.rows`); where it still splits, its lines are joined by detours round the
    zone (`_bypassed`).

    With `inset`, the bands are laid over the region less `inset` at either side across the lines, and the
    outermost bands reach over that margin too: a swath wider than the spacing by 2·`inset` still covers it, and
    fewer lines may fit.

    With `phase` in [0, 1], the rows are a full `spacing` apart (as many of them) and so span more than the
    region; the grid slides across the lines by that share of the excess: at 0 the first band starts where it
    would anyway and the last overhangs the region, at 1 the other way round (an outermost line may then lie just
    outside the region; its swath still reaches the edge). A zone may then fall between two lines rather than
    split one.

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
    if passing is not None:
        passing = Passing(geometry_to_sweep(passing.blocking, heading_deg), passing.shift, passing.reach,
                          passing.radius)
        shapely.prepare(passing.blocking)
    block = None if passing is None else passing.blocking
    if reg.is_empty:
        return Sweep(heading_deg, spacing, np.zeros(0), (), ())
    umin, vmin, umax, vmax = reg.bounds
    inset = inset if vmax - vmin > 2.0 * inset + 1e-9 else 0.0
    height = vmax - vmin - 2.0 * inset
    n = max(1, math.ceil(height / spacing - 1e-9))
    step = height / n if height > 0 else spacing
    shift = 0.0
    if phase is not None and height > 0:
        # a full spacing apart where the outermost lines stay within the region's extent, else as close to it as
        # lets them (the bands' shares overhang by `over` in all)
        over, step = n * spacing - height, spacing
        if over > inset + 0.5 * spacing:
            step = (height + inset) / (n - 0.5)
            over = inset + 0.5 * step
        shift = -phase * over
    edges = vmin + inset + shift + step * np.arange(n + 1)
    if phase is None:
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
        merged = _row_spans(polys, forb, block, v)
        if len(merged) > 1 and passing is not None and passing.shift > 0.0 and n > 1:
            lo = 0.0 if i == 0 and inset > 0.0 else -passing.shift  # an outermost line already stands in by the inset
            hi = 0.0 if i == n - 1 and inset > 0.0 else passing.shift
            v, merged = _shifted(polys, forb, passing.blocking, v, lo, hi, merged)
        bent: list[Bent] = [(span, ()) for span in merged]
        if passing is not None and passing.reach > 0.0 and len(merged) > 1:
            bent = _bypassed(merged, forb, passing, v)
        ids = []
        for (s0, s1, cs), bends in bent:
            ids.append(len(pieces))
            pieces.append(Piece(i, v, s0, s1, bends))
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
    return Sweep(heading_deg, step, rows, tuple(pieces), tuple(links),
                 (float(edges[0] - vmin), float(vmax - edges[-1])))


class SweepCache:
    """Sweeps of one scene at one spacing, built once per heading."""

    def __init__(self, region: BaseGeometry, forbidden: BaseGeometry, spacing: float, inset: float = 0.0,
                 passing: Passing | None = None, phase: float | None = None):
        self.region = region
        self.forbidden = forbidden
        self.spacing = spacing
        self.inset = inset
        self.passing = passing
        self.phase = phase
        self._built: dict[float, Sweep] = {}

    def get(self, heading_deg: float) -> Sweep:
        key = round(float(heading_deg) % 180.0, 9)
        if key not in self._built:
            self._built[key] = build_sweep(self.region, self.forbidden, key, self.spacing, self.inset,
                                            self.passing, self.phase)
        return self._built[key]
