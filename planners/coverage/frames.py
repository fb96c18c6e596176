"""Frames of coverage planning (seed 002 §2.1).

Mission polygons are lists of [north, east] pairs in metres (local NED). Inside, shapely works with x = east and
y = north, and every sweep works in its own frame where the survey lines are horizontal: u runs along the lines
(the line heading, degrees clockwise from north) and v across them. The sweep frame is a proper rotation of
(x, y), so left and right turns keep their sense.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray
from shapely.geometry import Polygon
from shapely.geometry.base import BaseGeometry

Array = NDArray[np.float64]


def polygon_ne(points: ArrayLike, what: str = "polygon") -> Polygon:
    """A shapely polygon (x = east, y = north) from [north, east] vertices; raises ValueError if it is not simple.

    >>> polygon_ne([[0, 0], [0, 10], [5, 10], [5, 0]]).bounds
    (0.0, 0.0, 10.0, 5.0)
    """
    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < 3 or not np.all(np.isfinite(pts)):
        raise ValueError(f"{what} must be at least three finite [north, east] pairs")
    poly = Polygon(pts[:, ::-1])
    if not poly.is_valid or poly.area <= 0.0:
        raise ValueError(f"{what} is not a simple polygon ({shapely.is_valid_reason(poly)})")
    return poly


def ne(xy: ArrayLike) -> Array:
    """[north, east] rows from (x = east, y = north) rows.

    >>> ne([[3.0, 4.0]]).tolist()
    [[4.0, 3.0]]
    """
    return np.ascontiguousarray(np.asarray(xy, dtype=float)[..., ::-1])


def sweep_matrix(heading_deg: float) -> Array:
    """M with uv = M @ xy: u along lines of heading `heading_deg` (clockwise from north), v to their left."""
    t = math.radians(heading_deg)
    return np.array([[math.sin(t), math.cos(t)], [-math.cos(t), math.sin(t)]])


def to_sweep(xy: ArrayLike, heading_deg: float) -> Array:
    """(u, v) of (x, y) points in the sweep frame of `heading_deg`.

    >>> to_sweep([[10.0, 5.0]], 90.0).round(6).tolist()    # lines run east: u = east, v = north
    [[10.0, 5.0]]
    >>> to_sweep([[10.0, 5.0]], 0.0).round(6).tolist()     # lines run north: u = north, v = west
    [[5.0, -10.0]]
    """
    return np.asarray(xy, dtype=float) @ sweep_matrix(heading_deg).T


def from_sweep(uv: ArrayLike, heading_deg: float) -> Array:
    """(x, y) of sweep-frame points; the inverse of `to_sweep`.

    >>> from_sweep(to_sweep([[1.0, 2.0]], 33.0), 33.0).round(9).tolist()
    [[1.0, 2.0]]
    """
    return np.asarray(uv, dtype=float) @ sweep_matrix(heading_deg)


def geometry_to_sweep(geom: BaseGeometry, heading_deg: float) -> Any:
    """A shapely geometry expressed in the sweep frame of `heading_deg`."""
    m = sweep_matrix(heading_deg).T
    return shapely.transform(geom, lambda c: c @ m)


def line_angle(heading_deg: float) -> float:
    """Math angle (radians, counter-clockwise from +x = east) of travel along +u for lines of `heading_deg`.

    >>> round(line_angle(90.0), 6), round(line_angle(0.0), 6)
    (0.0, 1.570796)
    """
    return math.pi / 2.0 - math.radians(heading_deg)


def heading_of(direction_xy: ArrayLike) -> float:
    """Line heading in [0, 180) degrees of an (x, y) direction.

    >>> heading_of([1.0, 1.0]), heading_of([0.0, -1.0])
    (45.0, 0.0)
    """
    d = np.asarray(direction_xy, dtype=float)
    return float(math.degrees(math.atan2(d[0], d[1])) % 180.0)
