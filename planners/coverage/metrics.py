"""How much of the free area a plan's survey passes cover (seed 002 §2.1: the meanders must cover the area minus
the forbidden zones). A pass covers the strip within half a swath of it, square at its ends (the sonar looks
across track, not ahead).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray
from shapely.geometry import Polygon
from shapely.geometry.base import BaseGeometry

from .frames import polygon_ne

if TYPE_CHECKING:
    from .plan import CoveragePlan

Array = NDArray[np.float64]


def swept(lines_xy: Sequence[Array], swath: float) -> BaseGeometry:
    """Union of the swaths of (2, 2) x, y passes, flat-capped.

    >>> round(swept([np.array([[0.0, 0.0], [10.0, 0.0]])], 4.0).area, 6)
    40.0
    """
    segs = [s for s in lines_xy if np.linalg.norm(s[1] - s[0]) > 1e-9]
    if not segs:
        return Polygon()
    strips = shapely.buffer(shapely.linestrings(np.stack(segs)), swath / 2.0, cap_style="flat")
    return shapely.union_all(strips)


def uncovered(lines_xy: Sequence[Array], free: BaseGeometry, swath: float) -> BaseGeometry:
    """The part of `free` no pass covers."""
    return free.difference(swept(lines_xy, swath))


def coverage_fraction(plan: CoveragePlan, area: ArrayLike, exclude: Sequence[ArrayLike], swath: float) -> float:
    """Share of the free area (area minus no-go zones) within swath/2 of the plan's survey passes.

    >>> from planners.coverage import meander
    >>> plan = meander([[0, 0], [0, 200], [100, 200], [100, 0]], spacing=25.0)
    >>> coverage_fraction(plan, [[0, 0], [0, 200], [100, 200], [100, 0]], [], swath=25.0) > 0.999
    True
    """
    poly = polygon_ne(area, "the survey area")
    zones = [polygon_ne(z, "a no-go zone") for z in exclude]
    free = poly.difference(shapely.union_all(zones)) if zones else poly
    if free.area <= 0.0:
        return 1.0
    lines_xy = [np.asarray(seg, dtype=float)[:, ::-1] for seg in plan.lines]
    return float(free.intersection(swept(lines_xy, swath)).area / free.area)
