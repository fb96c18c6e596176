"""GeoJSON (RFC 7946) of a mission or a run: WGS84 longitude/latitude in degrees, outer rings counter-clockwise and
holes clockwise, every ring closed. Each feature's `layer` property says what it is (geofence, survey_areas,
no_go_zones, planned_paths, objects, home, true_track, estimated_track, detections, photos, safety_events)."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import shapely
from shapely.geometry import Polygon

from mission.export.features import Feature
from mission.geodesy import ring_to_geodetic


def _ring(points_lonlat: list[tuple[float, float]], ccw: bool) -> list[list[float]]:
    ring = Polygon(points_lonlat).exterior
    if ring.is_ccw != ccw:
        ring = shapely.LinearRing(list(ring.coords)[::-1])
    return [[x, y] for x, y in ring.coords]  # closed: shapely repeats the first point last


def feature_geometry(feature: Feature, lat0: float, lon0: float) -> dict[str, Any]:
    """The GeoJSON geometry object of a feature."""
    rings = [ring_to_geodetic(r, lat0, lon0) for r in feature.rings_ne]
    if feature.geometry == "Point":
        return {"type": "Point", "coordinates": list(rings[0][0])}
    if feature.geometry == "LineString":
        return {"type": "LineString", "coordinates": [list(p) for p in rings[0]]}
    return {"type": "Polygon", "coordinates": [_ring(r, ccw=(k == 0)) for k, r in enumerate(rings)]}


def to_geojson(features: Sequence[Feature], lat0: float, lon0: float, name: str) -> dict[str, Any]:
    """A FeatureCollection of `features`, placed with the origin (lat0, lon0)."""
    return {"type": "FeatureCollection", "name": name,
            "features": [{"type": "Feature", "id": f"{f.layer}/{k}",
                          "geometry": feature_geometry(f, lat0, lon0),
                          "properties": {"layer": f.layer, "name": f.name, **f.properties}}
                         for k, f in enumerate(features)]}


def write_geojson(features: Sequence[Feature], lat0: float, lon0: float, name: str, out: Path) -> None:
    text = json.dumps(to_geojson(features, lat0, lon0, name), indent=1, allow_nan=False)
    out.write_text(text + "\n", encoding="utf-8")
