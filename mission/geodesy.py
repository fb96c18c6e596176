"""The mission's local NED frame on the globe: conversions between (north, east) metres and WGS84 (lat, lon).

The local frame is the tangent plane at the mission's `origin` (pymap3d's `geodetic2ned`, WGS84 ellipsoid). A
point of the plan lies on the sea surface (ellipsoid height 0), so a (north, east) pair maps to the one surface
point whose tangent-plane coordinates they are: `geodetic_to_ned` and `ned_to_geodetic` are exact inverses (to
micrometres over tens of kilometres), unlike a conversion that keeps the tangent plane's down = 0 (which is
centimetres off the surface 10 km out). Depths and altitudes are carried beside the point, never folded into it.

`localize` rewrites the `{lat, lon}` points of a raw mission document (geofence, survey areas and no-go zones,
transit targets) as local (north, east) before the models validate it; without a usable `origin` it leaves them
as they are and the models report each one where it stands.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pymap3d

from mission.errors import Diagnostic, MissionError

Array = np.ndarray
_SURFACE_ITERATIONS = 4  # each halves the height error by ~1e6 (the normals are within a degree of each other)


def geodetic_to_ned(lat: Any, lon: Any, lat0: float, lon0: float) -> tuple[Array, Array]:
    """(north, east) metres of surface points (lat, lon in degrees) in the tangent frame at (lat0, lon0).

    >>> n, e = geodetic_to_ned(0.0, 0.001, 0.0, 0.0)
    >>> round(float(n), 6), round(float(e), 3)
    (0.0, 111.319)
    """
    n, e, _ = pymap3d.geodetic2ned(np.asarray(lat, float), np.asarray(lon, float), 0.0, lat0, lon0, 0.0)
    return np.asarray(n, float), np.asarray(e, float)


def ned_to_geodetic(north: Any, east: Any, lat0: float, lon0: float) -> tuple[Array, Array]:
    """(lat, lon) degrees of the surface points whose tangent-frame coordinates are (north, east) metres.

    >>> lat, lon = ned_to_geodetic(3000.0, -4000.0, 42.95, 131.85)
    >>> n, e = geodetic_to_ned(lat, lon, 42.95, 131.85)
    >>> abs(float(n) - 3000.0) < 1e-6 and abs(float(e) + 4000.0) < 1e-6
    True
    """
    n, e = np.asarray(north, float), np.asarray(east, float)
    down = np.zeros_like(n)
    lat, lon = np.asarray(lat0, float), np.asarray(lon0, float)
    for _ in range(_SURFACE_ITERATIONS):  # walk down the local vertical until the point sits on the ellipsoid
        lat, lon, h = pymap3d.ned2geodetic(n, e, down, lat0, lon0, 0.0)
        down = down + np.asarray(h, float)
    return np.asarray(lat, float), np.asarray(lon, float)


def ring_to_geodetic(points_ne: Any, lat0: float, lon0: float) -> list[tuple[float, float]]:
    """[(lon, lat), ...] of a (north, east) polyline or ring (GeoJSON and KML order: longitude first)."""
    pts = np.asarray(points_ne, float).reshape(-1, 2)
    lat, lon = ned_to_geodetic(pts[:, 0], pts[:, 1], lat0, lon0)
    return [(float(a), float(b)) for a, b in zip(np.atleast_1d(lon), np.atleast_1d(lat), strict=True)]


def require_origin(mission: Any, what: str) -> tuple[float, float]:
    """The mission's origin (lat, lon), or a located MissionError saying that `what` needs one."""
    origin = getattr(mission, "origin", None)
    if origin is None:
        source = getattr(mission, "source", None) or f"mission '{getattr(mission, 'name', '?')}'"
        raise MissionError([Diagnostic(str(source), 1, 1, f"{what} needs the mission's geodetic origin: add "
                                                          "`origin: {lat: ..., lon: ...}` (degrees, WGS84)")])
    return float(origin.lat), float(origin.lon)


# -- {lat, lon} points in a raw mission document ----------------------------------------------------------------
def is_geodetic(value: Any) -> bool:
    """Whether a raw YAML value is written as a geodetic point (a mapping with `lat` or `lon`)."""
    return isinstance(value, dict) and ("lat" in value or "lon" in value)


def valid_geodetic(value: Any) -> bool:
    """A mapping of exactly finite `lat` in [-90, 90] and `lon` in [-180, 180]."""
    if not isinstance(value, dict) or set(value) != {"lat", "lon"}:
        return False
    lat, lon = value["lat"], value["lon"]
    numbers = all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in (lat, lon))
    return numbers and -90 <= lat <= 90 and -180 <= lon <= 180


def _usable_origin(data: dict[str, Any]) -> tuple[float, float] | None:
    origin = data.get("origin")
    if not isinstance(origin, dict) or not valid_geodetic(origin):
        return None
    return float(origin["lat"]), float(origin["lon"])


def _point(value: Any, origin: tuple[float, float]) -> Any:
    if not valid_geodetic(value):
        return value
    n, e = geodetic_to_ned(value["lat"], value["lon"], *origin)
    return [float(n), float(e)]


def _polygon(value: Any, origin: tuple[float, float]) -> Any:
    return [_point(p, origin) for p in value] if isinstance(value, list) else value


def localize(data: Any) -> Any:
    """A copy of a raw mission document with its `{lat, lon}` points as local [north, east] (transit targets as
    `{north, east}`), using its `origin`; the document itself when it has no usable origin or is not a mapping."""
    if not isinstance(data, dict):
        return data
    origin = _usable_origin(data)
    if origin is None:
        return data
    out = dict(data)
    safety = out.get("safety")
    if isinstance(safety, dict) and "geofence" in safety:
        out["safety"] = {**safety, "geofence": _polygon(safety["geofence"], origin)}
    route = out.get("route")
    if isinstance(route, list):
        out["route"] = [_localize_element(el, origin) for el in route]
    return out


def _localize_element(element: Any, origin: tuple[float, float]) -> Any:
    if not isinstance(element, dict):
        return element
    element = dict(element)
    survey = element.get("survey")
    if isinstance(survey, dict):
        survey = {**survey}
        if "area" in survey:
            survey["area"] = _polygon(survey["area"], origin)
        if isinstance(survey.get("exclude"), list):
            survey["exclude"] = [_polygon(z, origin) for z in survey["exclude"]]
        element["survey"] = survey
    transit = element.get("transit")
    if isinstance(transit, dict) and valid_geodetic(transit.get("to")):
        n, e = _point(transit["to"], origin)
        element["transit"] = {**transit, "to": {"north": n, "east": e}}
    return element
