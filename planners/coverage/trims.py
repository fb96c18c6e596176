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
from shapely.geometry.base import BaseGeometry

from .frames import from_sweep, to_sweep
from .sweep import Piece, Sweep


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
    v = np.array([q.v for q in p])
    corners = np.stack([np.stack([u0, v - half], 1), np.stack([u1, v - half], 1), np.stack([u1, v + half], 1),
                        np.stack([u0, v + half], 1)], axis=1)                     # (P, 4, 2) in the sweep frame
    bands = shapely.polygons(from_sweep(corners, sweep.heading_deg))
    todo = np.arange(len(p)) if covered is None else np.flatnonzero(shapely.intersects(bands, covered))
    shapely.prepare(need)
    parts = shapely.intersection(bands[todo], need)
    min_area = sliver * sweep.spacing**2
    extent = {k: (q.u0, q.u1) for k, q in enumerate(p)}
    for k, geom in zip(todo, parts, strict=True):
        big = [g for g in shapely.get_parts(geom) if g.area > min_area]
        if not big:
            del extent[int(k)]
            continue
        u = to_sweep(np.concatenate([shapely.get_coordinates(g) for g in big]), sweep.heading_deg)[:, 0]
        lo, hi = max(p[k].u0, float(u.min())), min(p[k].u1, float(u.max()))
        if hi > lo:
            extent[int(k)] = (lo, hi)
        else:
            del extent[int(k)]
    keep = sorted(extent)
    new_id = {old: new for new, old in enumerate(keep)}
    links = tuple((new_id[a], new_id[b]) for a, b in sweep.links if a in new_id and b in new_id)
    pieces = tuple(Piece(p[k].row, p[k].v, *extent[k]) for k in keep)
    return Sweep(sweep.heading_deg, sweep.spacing, sweep.rows, pieces, links)
