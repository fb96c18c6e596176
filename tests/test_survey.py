"""The survey element end to end: meander with the multibeam on, occupancy map at the estimated pose, height
and information maps, detections checked against the true objects of the reference world."""

import math

import pytest

from mission import load_mission, simulate

SURVEY_HEADER_SENSORS = "  mbes: {beams: 128, swath_deg: 120, max_range: 60, rate_hz: 5, range_sigma: 0.05}\n"

OBJECTS = """
objects:
  - id: manifold-1
    pose: {north: 150, east: 200, depth: 58, heading: 30}
    size: [8, 5, 2.5]
"""


def survey_mission(write_mission, name, area, altitude=15, extra_route=""):
    route = f"""
  - id: go
    transit: {{to: {{north: {area[0][0]}, east: {area[0][1]}}}, depth: 35}}
  - id: look
    survey: {{area: {area}, altitude: {altitude}, overlap: 20%, heading: auto, resolution: 0.5}}
    actions: [map, detect_objects]
{extra_route}"""
    path = write_mission(name, route, OBJECTS)
    path.write_text(path.read_text().replace("  usbl: {sigma: 1.5, rate_hz: 0.5}\n",
                                             "  usbl: {sigma: 1.5, rate_hz: 0.5}\n" + SURVEY_HEADER_SENSORS))
    return load_mission(path)


@pytest.fixture(scope="module")
def manifold_run(tmp_path_factory):
    from conftest import HEADER

    folder = tmp_path_factory.mktemp("survey")

    def write(name, route, extra=""):
        path = folder / f"{name}.yaml"
        path.write_text(f"name: {name}\n{HEADER}\n{extra}\nroute:\n{route}")
        return path

    mission = survey_mission(write, "manifold", [[120, 170], [120, 240], [190, 240], [190, 170]])
    return simulate(mission, seed=2, out=folder / "run", plots=True)


def test_survey_completes_and_covers_the_free_area(manifold_run):
    look = next(e for e in manifold_run.metrics["elements"] if e["id"] == "look")
    assert look["status"] == "succeeded"
    assert look["coverage_percent"] >= 97.0
    assert look["turns"] >= 1 and look["path_length_m"] > 0


def test_manifold_is_detected_matched_to_the_database_within_2_m(manifold_run):
    look = next(e for e in manifold_run.metrics["elements"] if e["id"] == "look")
    assert look["false_alarms"] == 0 and look["missed"] == []
    manifold = [d for d in look["detections"] if d["true_object"] == "manifold-1"]
    assert len(manifold) == 1
    det = manifold[0]
    assert det["matched_id"] == "manifold-1"
    assert det["position_error_m"] <= 2.0
    assert det["height"] == pytest.approx(2.5, abs=0.6)  # skid + module above the seabed
    assert max(det["length"], det["width"]) == pytest.approx(8.0, abs=2.0)


def test_survey_writes_maps_and_its_figure(manifold_run):
    out = manifold_run.out
    assert (out / "maps" / "look.npz").is_file()
    assert (out / "plots" / "survey_look.png").stat().st_size > 20_000


def test_an_object_missing_from_the_database_is_marked_unknown(write_mission):
    mission = survey_mission(write_mission, "wellhead", [[190, 85], [190, 135], [240, 135], [240, 85]])
    result = simulate(mission, seed=3)
    unknown = result.report.knowledge.unknown_objects()
    assert len(unknown) == 1
    assert math.hypot(unknown[0].north - 215.0, unknown[0].east - 110.0) <= 2.0
    look = next(e for e in result.metrics["elements"] if e["id"] == "look")
    assert look["detections"][0]["matched_id"] is None and look["false_alarms"] == 0
