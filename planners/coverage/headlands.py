"""Headland passes round the no-go zones (seed 002 §2.1: the whole area outside the forbidden zones is covered,
with the shortest path).

Survey lines that stop a standoff short of a zone leave a strip that contour passes must fill anyway; once a pass
is flown all the way round a zone, its swath covers everything within about half a swath of the zone, and survey
lines laid there would cover it twice. The headland layout flies one ring round each (grown) zone and lays the
survey lines only over the core: the line region minus what the rings' passes cover, a small overlap kept so that
no sliver is left between the two. The ring follows the zone at the standoff with its corners turned on arcs of
the turning radius; its straight sides are the survey passes, so that the corner wedges their swaths miss are a
clean part of the core that the lines cover. The cell planner tries both layouts and keeps the
shorter.
"""

from __future__ import annotations

import math

import numpy as np
import shapely
from numpy.typing import NDArray
from shapely.geometry.base import BaseGeometry
from shapely.geometry.polygon import orient

from .metrics import swept
from .runs import Run
from .scene import QUAD, Scene

Array = NDArray[np.float64]
OVERLAP = 0.1          # share of the swath by which the core reaches under the rings' swaths
ENTRIES = 4            # places round a ring where it may be entered (each flown either way)


def headland_rings(scene: Scene) -> list[Array]:
    """Closed rings (first point repeated, counter-clockwise round the zone) at the standoff from the zones, their
    corners, convex and concave, arcs of the turning radius."""
    if not scene.has_zones:
        return []
    grown = scene.zones.buffer(scene.standoff, join_style="mitre", mitre_limit=2.0)
    if scene.radius > 0.0:
        r = scene.radius
        grown = grown.buffer(-r, join_style="mitre", mitre_limit=2.0).buffer(r, quad_segs=QUAD)     # convex
        grown = grown.buffer(r, quad_segs=QUAD).buffer(-r, quad_segs=QUAD)                         # concave
    return [np.asarray(orient(poly).exterior.coords) for poly in shapely.get_parts(grown)
            if poly.geom_type == "Polygon" and not poly.is_empty]


def ring_run(ring: Array, start: int, min_pass: float) -> Run:
    """The ring flown from the middle of its side `start`; its sides longer than `min_pass` are the survey passes
    (the short chords of the corner arcs are turns).

    >>> square = np.array([[0.0, 0.0], [100.0, 0.0], [100.0, 100.0], [0.0, 100.0], [0.0, 0.0]])
    >>> run = ring_run(square, 1, 10.0)
    >>> run.path[0].tolist(), run.path[-1].tolist(), len(run.lines), run.length
    ([100.0, 50.0], [100.0, 50.0], 5, 400.0)
    """
    pts = ring[:-1]
    n = len(pts)
    mid = 0.5 * (pts[start % n] + pts[(start + 1) % n])
    order = [(start + 1 + j) % n for j in range(n)]
    path = np.concatenate([mid[None], pts[order], mid[None]])
    seg = np.linalg.norm(np.diff(path, axis=0), axis=1)
    lines = tuple(path[k : k + 2].copy() for k in range(len(path) - 1) if seg[k] > min_pass)
    d = path[1] - path[0]
    angle = math.atan2(d[1], d[0])
    return Run(path, lines, angle, angle, 0)


def headland_tasks(scene: Scene, entries: int = ENTRIES) -> list[list[Run]]:
    """One task per ring: its runs entered at up to `entries` sides spread round it, each flown either way."""
    tasks = []
    for ring in headland_rings(scene):
        sides = np.linalg.norm(np.diff(ring, axis=0), axis=1)
        along = np.cumsum(sides) - 0.5 * sides
        # entries on the longest sides nearest evenly spread points round the ring
        long = np.flatnonzero(sides >= np.sort(sides)[-min(len(sides), 2 * entries)])
        picks = sorted({int(long[np.argmin(np.abs(along[long] - f * sides.sum() / entries))]) for f in range(entries)})
        variants = []
        for k in picks:
            run = ring_run(ring, k, 2.0 * scene.radius)
            variants.extend([run, run.reversed()])
        tasks.append(variants)
    return tasks


def core_region(scene: Scene, rings: list[Run], overlap: float = OVERLAP) -> BaseGeometry:
    """The part of the line region the ring passes leave uncovered, grown back by `overlap` swaths.

    >>> from shapely.geometry import Point
    >>> scene = Scene.build([[0, 0], [0, 600], [600, 600], [600, 0]],
    ...                     [[[250, 250], [250, 350], [350, 350], [350, 250]]], 6.0, 2.0, 50.0)
    >>> core = core_region(scene, [t[0] for t in headland_tasks(scene)])
    >>> [bool(core.contains(Point(300, y))) for y in (225, 215)]   # the ring, 8 m out, covers 20 m either side
    [False, True]
    """
    if not rings:
        return scene.region
    covered = swept([seg for run in rings for seg in run.lines], scene.swath * (1.0 - 2.0 * overlap))
    return scene.region.difference(covered)
