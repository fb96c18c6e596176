"""Contour passes round the no-go zones (seed 002 §2.1: the whole area outside the forbidden zones is covered).

Survey lines stop a standoff short of a zone, to leave room for the turn, and meet its slanted sides in steps;
the strip they leave is covered by passes that follow the zone at the standoff, on a ring whose corners the
vehicle can fly (the zone grown by the standoff, its concave corners rounded to the turning radius). Only the
stretches of ring whose swath reaches uncovered free area are flown (a segment is needed if its own swath, square
at the ends as the coverage is counted, covers some of it; short gaps between needed segments are flown through,
unless the planner orders the stretches among its cells itself), the most useful first, until what stays uncovered
is within the tolerance.
"""

from __future__ import annotations

import heapq

import numpy as np
import shapely
from numpy.typing import NDArray
from shapely.geometry.base import BaseGeometry

from .runs import Run, polyline_run
from .scene import QUAD, Scene

Array = NDArray[np.float64]


def contour_rings(scene: Scene, spacing: float) -> list[Array]:
    """Closed rings (first point repeated at the end) round the zones, points at most spacing/4 apart."""
    if not scene.has_zones:
        return []
    grown = scene.zones.buffer(scene.standoff, quad_segs=QUAD)
    if scene.radius > 0.0:
        grown = grown.buffer(scene.radius, quad_segs=QUAD).buffer(-scene.radius, quad_segs=QUAD)
    rings = []
    for poly in shapely.get_parts(grown):
        if poly.geom_type != "Polygon":
            continue
        for ring in [poly.exterior, *poly.interiors]:
            rings.append(np.asarray(shapely.segmentize(ring, spacing / 4.0).coords))
    return rings


def _stretches(need: NDArray[np.bool_], ring: Array, bridge: float) -> list[Array]:
    """Stretches of a closed ring through the points that need it; gaps shorter than `bridge` are flown too.

    >>> square = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0], [0.0, 0.0]])
    >>> [a.tolist() for a in _stretches(np.array([True, True, False, False]), square, bridge=5.0)]
    [[[0.0, 0.0], [10.0, 0.0]]]
    """
    pts = ring[:-1]
    n = len(pts)
    if not need.any():
        return []
    seg = np.linalg.norm(np.diff(ring, axis=0), axis=1)          # seg[k]: pts[k] → pts[k+1]
    gaps = []                                                    # (first free index, length in points, metres)
    k0 = int(np.flatnonzero(need)[0])
    k = k0
    while True:                                                  # walk once round from a needed point
        k1 = (k + 1) % n
        if not need[k1]:
            j = k1
            run = 0
            metres = seg[k]
            while not need[j]:
                metres += seg[j]
                run += 1
                j = (j + 1) % n
            gaps.append((k1, run, metres))
            k = j
        else:
            k = k1
        if k == k0:
            break
    gaps = [g for g in gaps if g[2] > bridge]
    if not gaps:
        return [ring.copy()]
    out = []
    for i, (start, run, _) in enumerate(gaps):
        first = (start + run) % n                                # first needed point after this gap
        end_start = gaps[(i + 1) % len(gaps)][0]                 # first free point of the next gap
        idx = [first]
        j = (first + 1) % n
        while j != end_start:
            idx.append(j)
            j = (j + 1) % n
        out.append(pts[idx])
    return out


def _needed(ring: Array, residual: BaseGeometry, swath: float) -> NDArray[np.bool_]:
    """Which points of a closed ring a pass must fly through: the ends of the segments whose swath (square at the
    ends, as `metrics.swept` counts it) covers more than a sliver of `residual`."""
    segs = shapely.linestrings(np.stack([ring[:-1], ring[1:]], axis=1))
    strips = shapely.buffer(segs, swath / 2.0, cap_style="flat")
    parts = shapely.get_parts(residual)
    strip_idx, part_idx = shapely.STRtree(parts).query(strips, predicate="intersects")
    area = np.zeros(len(strips))
    if len(strip_idx):
        np.add.at(area, strip_idx, shapely.area(shapely.intersection(strips[strip_idx], parts[part_idx])))
    hit = area > 1e-3 * swath                              # more than a strip a millimetre wide across the swath
    return hit | np.roll(hit, 1)                           # point k ends segment k - 1 and starts segment k


def contour_runs(scene: Scene, residual: BaseGeometry, spacing: float, tolerance: float,
                 bridge: float | None = None) -> list[Run]:
    """Contour passes needed so that at most `tolerance` (a fraction of the free area) of `residual`, the free
    area the lines leave uncovered, stays uncovered. Gaps shorter than `bridge` (default: the larger of twice the
    standoff and the spacing) between the stretches needed are flown through; a planner that orders the passes
    among its other tasks may bridge nothing, and fly from one stretch to the next only where that is shortest."""
    if not scene.has_zones:
        return []
    budget = tolerance * scene.free.area
    if residual.area <= budget:
        return []
    arcs: list[Array] = []
    covers: list[BaseGeometry] = []
    for ring in contour_rings(scene, spacing):
        need = _needed(ring, residual, scene.swath)
        gap = max(2.0 * scene.standoff, spacing) if bridge is None else bridge
        for arc in _stretches(need, ring, gap):
            if len(arc) < 2:
                continue
            arcs.append(arc)
            covers.append(shapely.buffer(shapely.linestrings(arc), scene.swath / 2.0, cap_style="flat"))
    # greedy set cover, lazily: a pass's gain only shrinks as others are chosen. What is left uncovered is kept
    # as the residual's parts, each behind the extent it started with: a pass meets only the parts near it
    left = _Parts(residual)
    gains = [left.area_in(c) for c in covers]
    heap = [(-g, k) for k, g in enumerate(gains) if g > 0.0]
    heapq.heapify(heap)
    runs = []
    while heap and left.area > budget:
        _, k = heapq.heappop(heap)
        gain = left.area_in(covers[k])
        if heap and gain < -heap[0][0] - 1e-9:
            if gain > 0.0:
                heapq.heappush(heap, (-gain, k))
            continue
        if gain <= 0.0:
            break
        runs.append(polyline_run(arcs[k]))
        left.remove(covers[k])
    return runs


class _Parts:
    """An area as its separate parts behind a tree of their first extents (parts only shrink), so that a pass's
    overlap and what it leaves are found from the few parts near it."""

    def __init__(self, geom: BaseGeometry):
        self.parts = shapely.get_parts(geom)
        self.tree = shapely.STRtree(self.parts)
        self.areas = shapely.area(self.parts)
        self.area = float(self.areas.sum())

    def area_in(self, cover: BaseGeometry) -> float:
        near = self.tree.query(cover)
        return float(shapely.area(shapely.intersection(self.parts[near], cover)).sum()) if len(near) else 0.0

    def remove(self, cover: BaseGeometry) -> None:
        near = self.tree.query(cover)
        if len(near):
            self.parts[near] = shapely.difference(self.parts[near], cover)
            new = shapely.area(self.parts[near])
            self.area -= float(self.areas[near].sum() - new.sum())
            self.areas[near] = new
