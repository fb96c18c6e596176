"""Survey lines shortened where other passes already cover their band (seed 002 §2.1: cover the area with the
shortest path, without sweeping anything twice).

Lines run to the standoff from a no-go zone, and the contour passes that fill the strip the lines leave there
cover half a swath either side of themselves, so the last stretch of each line next to a zone is swept twice.
A line is needed only over the part of its band that no other pass covers: it is cut back to that, and dropped
if nothing of its band is left. Every free point of a band stays covered, by the line or by the other passes.
"""

from __future__ import annotations

import numpy as np
import shapely
from numpy.typing import NDArray
from shapely.geometry.base import BaseGeometry

from .frames import from_sweep, to_sweep
from .sweep import Sweep

Array = NDArray[np.float64]


def trim_to_need(sweep: Sweep, need: BaseGeometry, covered: BaseGeometry | None = None,
                 sliver: float = 1e-3) -> Sweep:
    """`sweep` with each line cut to the extent of the part of its band in `need` (x, y): the free area the other
    passes leave uncovered. Only bands meeting `covered` (what the other passes cover; default: all bands) can
    change. Parts smaller than `sliver`·spacing² are ignored; lines with nothing left are dropped (with their
    links).

    >>> from shapely.geometry import box
    >>> from .sweep import build_sweep
    >>> sweep = build_sweep(box(0, 0, 400, 100), box(0, 0, 0, 0), 90.0, 50.0)       # two rows, lines run east
    >>> cut = trim_to_need(sweep, box(0, 0, 300, 50).union(box(0, 50, 400, 100)))   # east end of row 0 covered
    >>> [(p.row, round(p.u0), round(p.u1)) for p in cut.pieces], cut.links
    ([(0, 0, 300), (1, 0, 400)], ((0, 1),))
    """
    p = sweep.pieces
    if not p:
        return sweep
    half = (0.5 - 1e-6) * sweep.spacing       # just inside the band, so that a touching neighbour adds nothing
    u0 = np.array([q.u0 for q in p])
    u1 = np.array([q.u1 for q in p])
    v = sweep.rows[[q.row for q in p]]                  # the bands' middles (a line may be shifted off it)
    v_lo, v_hi = v - half - _below(sweep), v + half + _above(sweep)
    boxes = np.stack([u0, v_lo, u1, v_hi], axis=1)                                 # (P, 4) in the sweep frame
    if covered is None:
        todo = np.arange(len(p))
    else:
        corners = np.stack([boxes[:, [0, 1]], boxes[:, [2, 1]], boxes[:, [2, 3]], boxes[:, [0, 3]]], axis=1)
        todo = np.flatnonzero(shapely.intersects(shapely.polygons(from_sweep(corners, sweep.heading_deg)), covered))
    lo, hi = _extents(boxes[todo], np.arange(len(todo)), len(todo), need, sweep.heading_deg,
                      sliver * sweep.spacing**2)
    extent = {k: (q.u0, q.u1) for k, q in enumerate(p)}
    for i, k in enumerate(todo.tolist()):
        a, b = max(p[k].u0, float(lo[i])), min(p[k].u1, float(hi[i]))
        if b > a:
            extent[k] = (a, b)
        else:
            del extent[k]
    return _with_extents(sweep, extent)


def trim_to_neighbours(sweep: Sweep, need: BaseGeometry, swath: float, sliver: float = 1e-3) -> Sweep:
    """`sweep` with each line cut further to what its neighbours' swaths leave of its band's `need` (x, y).

    A swath wider than the spacing reaches (swath − spacing)/2 into each neighbouring band. Where a boundary
    slants across the lines, a band's far tip lies along one of its edges, under the swath of the next line,
    which runs further: the line is cut back to the rest of its band. The neighbours are taken as they are in
    `sweep`; each line keeps the middle of its band, so what it leaves to a neighbour the neighbour keeps.

    >>> from shapely.geometry import Polygon
    >>> from .sweep import build_sweep
    >>> wedge = Polygon([(0, 0), (400, 0), (0, 100)])            # the hypotenuse slants across eastward lines
    >>> sweep = build_sweep(wedge, Polygon(), 90.0, 50.0)        # row 1's tip lies under row 0's swath
    >>> [round(p.u1) for p in sweep.pieces], [round(p.u1) for p in trim_to_neighbours(sweep, wedge, 62.5).pieces]
    ([400, 200], [400, 176])
    """
    p = sweep.pieces
    if not p or swath <= sweep.spacing:
        return sweep
    s = sweep.spacing
    reach = 0.5 * (swath - s) * 0.95                       # a little under the neighbours' reach, for safety
    half = (0.5 - 1e-6) * s
    below, above = _below(sweep), _above(sweep)
    mid = sweep.rows[[q.row for q in p]]                # the bands' middles (a line may be shifted off it)
    by_row: dict[int, list[int]] = {}
    for k, q in enumerate(p):
        by_row.setdefault(q.row, []).append(k)
    # the middle of each band first: where its part of `need` already reaches both ends of the line, the strips
    # along the band's edges cannot change the line's extent
    middle = np.array([(q.u0, mid[k] - half + reach, q.u1, mid[k] + half - reach) for k, q in enumerate(p)])
    lo, hi = _extents(middle, np.arange(len(p)), len(p), need, sweep.heading_deg, sliver * s**2)
    boxes: list[tuple[float, float, float, float]] = []
    owner: list[int] = []
    for k, q in enumerate(p):
        if lo[k] <= q.u0 and hi[k] >= q.u1:
            continue
        for side in (1, -1):                                # the strips along the band's upper and lower edges
            if side > 0:
                lo_v, hi_v = mid[k] + half - reach, mid[k] + half + float(above[k])
            else:
                lo_v, hi_v = mid[k] - half - float(below[k]), mid[k] - half + reach
            # a neighbour shifted away from this band reaches less far into it: it is not counted on
            cover = sorted((p[m].u0, p[m].u1) for m in by_row.get(q.row + side, [])
                           if side * (p[m].v - mid[m]) <= 1e-9)
            at = q.u0
            for a, b in cover:
                if b <= at or a >= q.u1:
                    continue
                if a > at:
                    boxes.append((at, lo_v, a, hi_v))
                    owner.append(k)
                at = max(at, b)
            if at < q.u1:
                boxes.append((at, lo_v, q.u1, hi_v))
                owner.append(k)
    if boxes:
        s_lo, s_hi = _extents(np.array(boxes), np.array(owner), len(p), need, sweep.heading_deg, sliver * s**2)
        lo, hi = np.minimum(lo, s_lo), np.maximum(hi, s_hi)
    extent: dict[int, tuple[float, float]] = {}
    for k, q in enumerate(p):
        a, b = max(q.u0, float(lo[k])), min(q.u1, float(hi[k]))
        if b > a:
            extent[k] = (a, b)
    return _with_extents(sweep, extent)


def _extents(boxes: Array, owner: NDArray[np.int64], count: int, need: BaseGeometry, heading_deg: float,
             min_area: float) -> tuple[Array, Array]:
    """Per owner (of `count`), the least and greatest u of the parts larger than `min_area` of `need` (x, y)
    within its (u0, v0, u1, v1) sweep-frame `boxes` (inf, −inf where there are none)."""
    corners = np.stack([boxes[:, [0, 1]], boxes[:, [2, 1]], boxes[:, [2, 3]], boxes[:, [0, 3]]], axis=1)
    shapely.prepare(need)
    parts, index = shapely.get_parts(shapely.intersection(shapely.polygons(from_sweep(corners, heading_deg)), need),
                                     return_index=True)
    big = shapely.area(parts) > min_area
    coords, which = shapely.get_coordinates(parts[big], return_index=True)
    u = to_sweep(coords, heading_deg)[:, 0]
    lo, hi = np.full(count, np.inf), np.full(count, -np.inf)
    np.minimum.at(lo, owner[index[big][which]], u)
    np.maximum.at(hi, owner[index[big][which]], u)
    return lo, hi


def _below(sweep: Sweep) -> Array:
    """How far each piece's band reaches below its spacing-wide share (the first row's by `Sweep.reach`)."""
    return np.array([sweep.reach[0] if q.row == 0 else 0.0 for q in sweep.pieces])


def _above(sweep: Sweep) -> Array:
    """How far each piece's band reaches above its spacing-wide share (the last row's by `Sweep.reach`)."""
    last = len(sweep.rows) - 1
    return np.array([sweep.reach[1] if q.row == last else 0.0 for q in sweep.pieces])


def _with_extents(sweep: Sweep, extent: dict[int, tuple[float, float]]) -> Sweep:
    """`sweep` keeping the pieces in `extent`, with those extents, and the links between them."""
    p = sweep.pieces
    keep = sorted(extent)
    new_id = {old: new for new, old in enumerate(keep)}
    links = tuple((new_id[a], new_id[b]) for a, b in sweep.links if a in new_id and b in new_id)
    pieces = tuple(p[k].cut(*extent[k]) for k in keep)
    return Sweep(sweep.heading_deg, sweep.spacing, sweep.rows, pieces, links, sweep.reach)
