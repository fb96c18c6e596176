"""Geodetic frames: (north, east) ↔ (lat, lon) round-trips within a centimetre over 10 km, `{lat, lon}` points in a
mission load as the same local points, and one without an origin is a located error."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from mission.geodesy import geodetic_to_ned, ned_to_geodetic
from mission.language import mission_schema, validate_mission_file

ORIGIN = (42.95, 131.85)
AREA_NE = [(9000.0, 9000.0), (9000.0, 9400.0), (9300.0, 9400.0), (9300.0, 9000.0)]


def test_local_points_round_trip_through_lat_lon_within_a_centimetre_over_10_km() -> None:
    rng = np.random.default_rng(3)
    ne = rng.uniform(-10_000.0, 10_000.0, size=(500, 2))
    for lat0, lon0 in (ORIGIN, (-70.0, -179.9), (0.0, 0.0)):
        lat, lon = ned_to_geodetic(ne[:, 0], ne[:, 1], lat0, lon0)
        n, e = geodetic_to_ned(lat, lon, lat0, lon0)
        assert np.hypot(n - ne[:, 0], e - ne[:, 1]).max() < 0.01
    # and the points are where a geodesic says: 10 km due north is ~0.0899 degrees of latitude at 43 N
    lat, lon = ned_to_geodetic(10_000.0, 0.0, *ORIGIN)
    assert abs(float(lat) - ORIGIN[0] - 0.08995) < 2e-4 and abs(float(lon) - ORIGIN[1]) < 1e-12


def _mission(tmp_path: Path, origin: bool, area: list[object], to: object) -> Path:
    doc: dict[str, object] = {
        "name": "geo", "sensors": {"mbes": {}, "usbl": {}},
        "route": [{"id": "go", "transit": {"to": to, "depth": 10}},
                  {"id": "map", "survey": {"area": area, "altitude": 20}}]}
    if origin:
        doc["origin"] = {"lat": ORIGIN[0], "lon": ORIGIN[1]}
    path = tmp_path / "geo.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False), encoding="utf-8")
    return path


def _geo(n: float, e: float) -> dict[str, float]:
    lat, lon = ned_to_geodetic(n, e, *ORIGIN)
    return {"lat": float(lat), "lon": float(lon)}


def test_lat_lon_polygons_and_points_load_as_the_same_local_geometry(tmp_path: Path) -> None:
    path = _mission(tmp_path, True, [_geo(n, e) for n, e in AREA_NE], _geo(8990.0, 8995.0))
    mission, diags = validate_mission_file(path, environment=False)
    assert mission is not None, diags
    survey, transit = mission.route[1].survey, mission.route[0].transit
    assert survey is not None and transit is not None and not isinstance(transit.to, str)
    assert np.abs(np.array(survey.area) - np.array(AREA_NE)).max() < 0.01
    assert abs(transit.to.north - 8990.0) < 0.01 and abs(transit.to.east - 8995.0) < 0.01


def test_a_lat_lon_point_without_an_origin_is_an_error_at_that_point(tmp_path: Path) -> None:
    area: list[object] = [list(p) for p in AREA_NE]
    area[2] = _geo(*AREA_NE[2])
    path = _mission(tmp_path, False, area, {"north": 0.0, "east": 0.0})
    mission, diags = validate_mission_file(path, environment=False)
    assert mission is None
    (diag,) = [d for d in diags if "origin" in d.message]
    assert "lat:" in path.read_text().splitlines()[diag.line - 1]


def test_a_mission_without_an_origin_has_none_rather_than_zero_zero(tmp_path: Path) -> None:
    mission, diags = validate_mission_file(_mission(tmp_path, False, [list(p) for p in AREA_NE], "home"),
                                           environment=False)
    assert mission is not None and mission.origin is None, diags


def test_the_schema_accepts_lat_lon_points() -> None:
    import jsonschema

    doc = {"name": "geo", "origin": {"lat": 1.0, "lon": 2.0},
           "route": [{"id": "go", "transit": {"to": {"lat": 1.0, "lon": 2.001}}},
                     {"id": "map", "survey": {"area": [{"lat": 1, "lon": 2}, [0, 10], [10, 10]], "altitude": 20}}]}
    jsonschema.validate(doc, mission_schema())
