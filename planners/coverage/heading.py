"""Choosing the line direction (seed 002 §2.1: meanders with the fewest turns and the shortest path).

For every candidate heading the free area is sliced by rows at the line spacing without building any geometry:
the crossings of each row with the oriented boundary edges give the number of lines (turns) and their total
length in closed form (exits minus entries along the row), for all headings at once with array arithmetic.
The few best headings are then planned in full.
"""

from __future__ import annotations

import math

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray
from shapely.geometry.base import BaseGeometry
from shapely.geometry.polygon import orient

from .frames import heading_of

Array = NDArray[np.float64]


def oriented_edges(geom: BaseGeometry) -> Array:
    """(E, 2, 2) boundary edges of a (multi)polygon, exteriors counter-clockwise and holes clockwise."""
    edges = []
    for poly in shapely.get_parts(geom):
        if poly.geom_type != "Polygon" or poly.is_empty:
            continue
        poly = orient(poly, sign=1.0)
        for ring in [poly.exterior, *poly.interiors]:
            c = np.asarray(ring.coords)
            edges.append(np.stack([c[:-1], c[1:]], axis=1))
    return np.concatenate(edges) if edges else np.zeros((0, 2, 2))


def edge_headings(geom: BaseGeometry, min_length: float = 0.0) -> Array:
    """Line headings (degrees in [0, 180)) parallel to the boundary edges longer than `min_length`.

    >>> from shapely.geometry import box
    >>> sorted(set(edge_headings(box(0, 0, 4, 1)).tolist()))
    [0.0, 90.0]
    """
    e = oriented_edges(geom)
    d = e[:, 1] - e[:, 0]
    keep = np.linalg.norm(d, axis=1) > min_length
    return np.array([heading_of(v) for v in d[keep]])


def row_statistics(
    geom: BaseGeometry, headings_deg: ArrayLike, spacing: float, chunk: int = 16
) -> tuple[Array, Array, Array]:
    """Per heading: number of lines, their total length, and the total gap between lines sharing a row.

    A line reaches as far as its band of the area does (so that the swath covers the whole band): the length of
    a row is the extent of the area over the band, less the gaps between the row's lines.

    >>> from shapely.geometry import box
    >>> lines, length, gaps = row_statistics(box(0, 0, 400, 100), [90.0, 0.0], 50.0)
    >>> lines.tolist(), length.round(6).tolist(), gaps.tolist()
    ([2.0, 8.0], [800.0, 800.0], [0.0, 0.0])
    >>> lines, length, _ = row_statistics(box(0, 0, 400, 100), [45.0], 50.0)   # bands overhang the corners
    >>> int(lines[0]), round(float(length[0]), 1)
    (8, 1237.4)
    """
    h = np.atleast_1d(np.asarray(headings_deg, dtype=float))
    e = oriented_edges(geom)
    lines = np.zeros(len(h))
    length = np.zeros(len(h))
    gaps = np.zeros(len(h))
    if len(e) == 0:
        return lines, length, gaps
    for s in range(0, len(h), chunk):
        t = np.radians(h[s : s + chunk])[:, None]
        st, ct = np.sin(t), np.cos(t)
        u1 = e[None, :, 0, 0] * st + e[None, :, 0, 1] * ct
        v1 = -e[None, :, 0, 0] * ct + e[None, :, 0, 1] * st
        u2 = e[None, :, 1, 0] * st + e[None, :, 1, 1] * ct
        v2 = -e[None, :, 1, 0] * ct + e[None, :, 1, 1] * st
        vmin = np.minimum(v1, v2).min(axis=1)
        vmax = np.maximum(v1, v2).max(axis=1)
        n = np.maximum(1, np.ceil((vmax - vmin) / spacing - 1e-9)).astype(int)
        step = (vmax - vmin) / n
        k = np.arange(n.max())
        valid = k[None, :] < n[:, None]
        lo = vmin[:, None] + k[None, :] * step[:, None]                   # (A, R) band edges and middles
        levels = [lo, lo + 0.5 * step[:, None], lo + step[:, None]]
        umin = np.full(lo.shape, np.inf)
        umax = np.full(lo.shape, -np.inf)
        for j, vr in enumerate(levels):
            below1 = v1[:, None, :] <= vr[:, :, None]                      # (A, R, E)
            cross = (below1 != (v2[:, None, :] <= vr[:, :, None])) & valid[:, :, None]
            dv = (v2 - v1)[:, None, :]
            with np.errstate(divide="ignore", invalid="ignore"):
                u = u1[:, None, :] + (vr[:, :, None] - v1[:, None, :]) / dv * (u2 - u1)[:, None, :]
            umin = np.minimum(umin, np.where(cross, u, np.inf).min(axis=2))
            umax = np.maximum(umax, np.where(cross, u, -np.inf).max(axis=2))
            if j == 1:                                                     # the row itself
                up = cross & (dv > 0)
                down = cross & (dv < 0)
                row_len = np.where(up, u, 0.0).sum(axis=2) - np.where(down, u, 0.0).sum(axis=2)
                count = cross.sum(axis=2)
                span = np.where(cross, u, -np.inf).max(axis=2) - np.where(cross, u, np.inf).min(axis=2)
                row_gap = np.where(count > 0, np.maximum(span - row_len, 0.0), 0.0)
        inside = (v1[:, None, :] >= lo[:, :, None]) & (v1[:, None, :] <= lo[:, :, None] + step[:, None, None])
        inside &= valid[:, :, None]
        umin = np.minimum(umin, np.where(inside, u1[:, None, :], np.inf).min(axis=2))
        umax = np.maximum(umax, np.where(inside, u1[:, None, :], -np.inf).max(axis=2))
        band = np.where(np.isfinite(umin) & np.isfinite(umax), umax - umin, 0.0)
        pieces = np.maximum(count // 2, np.where(band > 0, 1, 0))
        lines[s : s + chunk] = pieces.sum(axis=1)
        length[s : s + chunk] = np.maximum(band - row_gap, 0.0).sum(axis=1)
        gaps[s : s + chunk] = row_gap.sum(axis=1)
    return lines, length, gaps


def shortlist(headings_deg: Array, keys: tuple[Array, ...], count: int, apart_deg: float = 4.0) -> Array:
    """The `count` best headings by `keys` (last key first, as `np.lexsort`), no two within `apart_deg`."""
    chosen: list[float] = []
    for i in np.lexsort(keys):
        hh = float(headings_deg[i])
        if all(min(abs(hh - c), 180.0 - abs(hh - c)) >= apart_deg for c in chosen):
            chosen.append(hh)
            if len(chosen) == count:
                break
    return np.array(chosen)


def sweep_score(lines: Array, length: Array, gaps: Array, turn_length: float) -> Array:
    """Rough path length of a single-direction sweep: lines, one turn per line, and detours across gaps."""
    return length + np.maximum(lines - 1.0, 0.0) * turn_length + 1.5 * gaps


def heading_grid(step_deg: float) -> Array:
    """Headings 0, step, 2·step … below 180 degrees."""
    if step_deg <= 0.0:
        raise ValueError(f"angle step must be positive, got {step_deg}")
    return np.arange(0.0, 180.0, step_deg)


def merge_headings(*groups: ArrayLike, tol_deg: float = 0.25) -> Array:
    """Distinct headings (mod 180) from several groups, near-duplicates dropped."""
    allh = np.concatenate([np.atleast_1d(np.asarray(g, dtype=float)) for g in groups]) % 180.0
    out: list[float] = []
    for hh in np.sort(allh):
        if not out or hh - out[-1] > tol_deg:
            out.append(float(hh))
    if len(out) > 1 and out[0] + 180.0 - out[-1] <= tol_deg:
        out.pop()
    return np.array(out)


def u_turn_length(spacing: float, radius: float) -> float:
    """Length of the turn between adjacent lines `spacing` apart (U-turn if spacing ≥ 2R, Ω-turn otherwise).

    >>> round(u_turn_length(50.0, 6.0), 2), round(u_turn_length(10.0, 6.0), 2)
    (56.85, 28.72)
    """
    if radius <= 0.0:
        return spacing
    if spacing >= 2.0 * radius:
        return math.pi * radius + spacing - 2.0 * radius
    h = math.sqrt(4.0 * radius**2 - (spacing / 2.0 + radius) ** 2)
    phi = math.atan2(spacing / 2.0 + radius, h)
    return radius * (3.0 * math.pi - 4.0 * phi)
