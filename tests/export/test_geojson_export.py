"""GeoJSON and KML exports read back to the mission's NED geometry within a centimetre, 13 km from the origin."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import export_cases
import numpy as np
import pytest
import shapely
from shapely.geometry import Polygon, shape

from mission.export import export
from mission.geodesy import geodetic_to_ned
from mission.language import load_mission

ORIGIN = (42.95, 131.85)


@pytest.fixture
def mission_file(tmp_path: Path) -> Path:
    return export_cases.far_mission(tmp_path)


@pytest.fixture
def run_folder(tmp_path: Path) -> Path:
    return export_cases.synthetic_run(tmp_path)


def _to_ned(coords: np.ndarray) -> np.ndarray:
    n, e = geodetic_to_ned(coords[:, 1], coords[:, 0], *ORIGIN)
    return np.column_stack([n, e])


def _hausdorff_m(a: Polygon, b: Polygon) -> float:
    return float(shapely.hausdorff_distance(a, b, densify=0.25))


def test_geojson_polygons_read_back_through_shapely_equal_the_ned_polygons_within_1_cm(mission_file: Path,
                                                                                         tmp_path: Path) -> None:
    mission = load_mission(mission_file, environment=False)
    out = tmp_path / "far.geojson"
    export(mission_file, "geojson", out)
    doc = json.loads(out.read_text())
    by_layer: dict[str, list[dict[str, object]]] = {}
    for f in doc["features"]:
        by_layer.setdefault(f["properties"]["layer"], []).append(f)
    survey = mission.route[1].survey
    assert survey is not None and mission.safety.geofence is not None
    expected = {"geofence": mission.safety.geofence, "survey_areas": survey.area, "no_go_zones": survey.exclude[0]}
    for layer, ring_ne in expected.items():
        geom = shape(by_layer[layer][0]["geometry"])
        assert geom.exterior.is_ccw  # RFC 7946: outer rings counter-clockwise
        back = Polygon(_to_ned(np.asarray(geom.exterior.coords)))
        assert _hausdorff_m(back, Polygon(ring_ne)) < 0.01, layer
        corners = _to_ned(np.asarray(geom.exterior.coords))[:-1]
        assert np.min(np.linalg.norm(corners - np.asarray(ring_ne[0]), axis=1)) < 0.01


def test_geojson_planned_paths_start_home_and_carry_the_survey_altitude(mission_file: Path, tmp_path: Path) -> None:
    out = tmp_path / "far.geojson"
    export(mission_file, "geojson", out)
    paths = [f for f in json.loads(out.read_text())["features"] if f["properties"]["layer"] == "planned_paths"]
    assert [p["properties"]["element"] for p in paths] == ["out", "far-field", "back"]
    first = _to_ned(np.asarray(paths[0]["geometry"]["coordinates"]))
    assert np.allclose(first, [[0, 0], [9000, 9000]], atol=0.01)
    assert paths[1]["properties"]["altitude"] == 20.0 and paths[1]["properties"]["depth"] is None
    survey = _to_ned(np.asarray(paths[1]["geometry"]["coordinates"]))
    assert Polygon([[9000, 9000], [9000, 9400], [9300, 9400], [9300, 9000]]).buffer(7.0).contains(  # turns: 6 m radius
        shapely.MultiPoint(survey[1:]))


def test_kml_placemarks_read_back_to_the_ned_polygons_within_1_cm(mission_file: Path, tmp_path: Path) -> None:
    mission = load_mission(mission_file, environment=False)
    out = tmp_path / "far.kml"
    export(mission_file, "kml", out)
    ns = {"k": "http://www.opengis.net/kml/2.2"}
    root = ET.parse(out).getroot()
    folders = {f.findtext("k:name", namespaces=ns): f for f in root.iter(f"{{{ns['k']}}}Folder")}
    assert {"geofence", "survey_areas", "no_go_zones", "planned_paths", "objects", "home"} <= set(folders)
    text = folders["survey_areas"].find(".//k:outerBoundaryIs/k:LinearRing/k:coordinates", ns)
    assert text is not None and text.text is not None
    coords = np.array([[float(v) for v in c.split(",")[:2]] for c in text.text.split()])
    survey = mission.route[1].survey
    assert survey is not None
    assert _hausdorff_m(Polygon(_to_ned(coords)), Polygon(survey.area)) < 0.01


def test_a_run_exports_its_tracks_photos_and_safety_events_as_geojson(run_folder: Path, tmp_path: Path) -> None:
    out = tmp_path / "run.geojson"
    result = export(run_folder, "geojson", out)
    features = json.loads(out.read_text())["features"]
    assert result.count == len(features)
    layers = {f["properties"]["layer"]: f for f in features}
    assert len(layers["true_track"]["geometry"]["coordinates"]) == 120
    est = _to_ned(np.asarray(layers["estimated_track"]["geometry"]["coordinates"]))
    assert np.allclose(est[0], [9000.3, 8999.8], atol=0.01)
    photo = layers["photos"]
    assert photo["properties"]["file"] == "photos/t1_0.png"
    # the photo at t = 20 s sits on the estimated track at that time
    assert np.allclose(_to_ned(np.asarray([photo["geometry"]["coordinates"]])), [[9040.3, 9019.8]], atol=0.01)
    detection = layers["detections"]
    assert np.allclose(_to_ned(np.asarray([detection["geometry"]["coordinates"]])), [[9152.0, 9201.0]], atol=0.01)
    assert detection["properties"]["height"] is None  # GeoJSON is strict JSON: no NaN
    safety = [f["properties"]["event"] for f in features if f["properties"]["layer"] == "safety_events"]
    assert safety == ["safety_violation", "element_failed"]
