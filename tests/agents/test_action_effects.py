"""Each action of a route element does what it names, in the run folder and in `metrics.json` (`actions` block):
`map` writes the element's maps, `detect_objects` detects, `photograph` takes photographs, `record` and `model`
record the element's stereo pairs with the estimated camera poses, and `explore.sensor` is the sensor flown.

Small worlds, short elements, a small camera and no plots keep every run to seconds; each test compares an
element that asks for an action with one that does not, so an ignored action fails it."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

os.environ.setdefault("MUJOCO_GL", "egl")  # stereo pairs are rendered off-screen

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from mission import load_mission, simulate  # noqa: E402
from mission.events import read_events  # noqa: E402
from mission.frames import camera_pose  # noqa: E402
from mission.sim.run import RunResult  # noqa: E402
from mission.sim.stereo_record import read_stereo_recording  # noqa: E402

WORLD = """
name: crate
seabed: {north: [-60, 60], east: [-60, 60], resolution: 1.0, mean_depth: 40.0,
         roughness: {amplitude: 0.1, wavelength: 10, seed: 2}}
objects:
  - id: crate
    database: crate
    pose: {north: 10, east: 5, depth: 40, heading: 30}
    parts:
      - {shape: box, size: [4, 3, 1.5], at: [2, 1.5, -0.75], color: [0.7, 0.6, 0.3]}
"""

HEADER = """
world: world.yaml
seed: 4
home: {north: -10, east: -5, depth: 30}
sensors:
  mbes: {beams: 128, swath_deg: 120, max_range: 60, rate_hz: 5, range_sigma: 0.05}
  stereo: {width: 320, height: 240, fx: 270, baseline: 0.25, rate_hz: 2, max_range: 12}
  usbl: {sigma: 1.5, rate_hz: 0.5}
  dvl: {drift_percent: 0.5}
safety:
  geofence: [[-60, -60], [-60, 60], [60, 60], [60, -60]]
  max_depth: 120
"""


def run(tmp_path: Path, name: str, route: str, objects: str = "") -> RunResult:
    folder = tmp_path / name
    folder.mkdir()
    (folder / "world.yaml").write_text(WORLD, encoding="utf-8")
    (folder / "mission.yaml").write_text(f"name: {name}\n{HEADER}{objects}\nroute:\n{route}", encoding="utf-8")
    return simulate(load_mission(folder / "mission.yaml"), out=folder / "run", plots=False)


def element(result: RunResult, element_id: str) -> dict[str, Any]:
    return next(e for e in result.metrics["elements"] if e["id"] == element_id)


def test_record_writes_the_elements_pairs_with_estimated_left_camera_poses_and_only_its_own(tmp_path) -> None:
    result = run(tmp_path, "record", """
  - id: go
    transit: {to: {north: 10, east: 5}, depth: 34}
    actions: [record]
  - id: back
    transit: {to: {north: -10, east: -5}, depth: 34}
""")
    out = result.out
    assert out is not None
    go, back = element(result, "go"), element(result, "back")
    assert go["status"] == back["status"] == "succeeded"
    assert go["actions"]["record"] == "stereo/go" and back["actions"] == {}
    assert not (out / "stereo" / "back").exists()  # a transit on its own never switches the camera on
    recording = read_stereo_recording(out / "stereo" / "go")
    pairs = go["actions"]["recorded_pairs"]
    assert len(recording) == pairs >= 0.8 * 2.0 * go["duration_s"]  # the camera's 2 Hz over the element
    assert float(recording.K[0, 0]) == 270.0 and recording.baseline == 0.25
    assert (out / "stereo" / "go" / "calib.txt").is_file() and not (out / "stereo" / "go" / "nav.txt").exists()
    start = next(e["time"] for e in read_events(out / "events.jsonl")
                 if e["event"] == "element_started" and e["element"] == "go")
    assert start <= recording.times[0] and recording.times[-1] <= start + go["duration_s"] + 0.5
    # poses.txt is the estimate: the left camera at the navigation's pose of that tick, not the truth
    rows = {round(r[0], 6): r for r in result.vehicle.log.rows}
    truth = {round(t, 6): T for t, T in result.vehicle.log.frames}
    offsets = []
    for t, T in zip(recording.times, recording.poses, strict=True):
        row = rows[round(float(t), 6)]
        north, east, depth, heading = (float(row[k]) for k in (6, 7, 8, 9))
        expected = camera_pose(north, east, depth, heading, baseline=0.25)
        assert np.allclose(T[:3, :4], expected[:3, :4], atol=1e-6)
        offsets.append(float(np.linalg.norm(T[:3, 3] - truth[round(float(t), 6)][:3, 3])))
    assert 0.0 < max(offsets) < 5.0  # dead reckoning between USBL fixes: apart from the truth, by metres at most


def test_map_writes_the_elements_maps_and_detect_objects_finds_the_crate(tmp_path) -> None:
    area = "[[0, -5], [0, 15], [20, 15], [20, -5]]"
    result = run(tmp_path, "map", f"""
  - id: mapped
    survey: {{area: {area}, altitude: 12, resolution: 0.5}}
    actions: [map, detect_objects]
  - id: unmapped
    survey: {{area: {area}, altitude: 12, resolution: 0.5}}
""")
    out = result.out
    assert out is not None
    mapped, unmapped = element(result, "mapped"), element(result, "unmapped")
    assert mapped["actions"]["map"] == "maps/mapped.npz" and "map" not in unmapped["actions"]
    assert sorted(p.name for p in (out / "maps").iterdir()) == ["mapped.npz"]
    with np.load(out / "maps" / "mapped.npz") as maps:
        assert maps["depth"].ndim == 2 and np.isfinite(maps["depth"]).mean() > 0.5
    assert mapped["actions"]["detect_objects"] == len(mapped["detections"]) == 1
    assert mapped["detections"][0]["true_object"] == "crate"
    assert unmapped["detections"] == []  # flown and mapped internally, but nothing detected: not asked


PLATE = "objects:\n  - {id: crate, pose: {north: 10, east: 5, depth: 40, heading: 30}, size: [4, 3, 1.5]}\n"


@pytest.fixture(scope="module")
def photo_and_model(tmp_path_factory) -> tuple[RunResult, RunResult]:
    folder = tmp_path_factory.mktemp("actions")
    explore = "explore: {object: crate, sensor: stereo, planner: rrt-photo, safe_distance: 4, budget: 3min}"
    photos = run(folder, "photos", f"  - id: look\n    {explore}\n    actions: [photograph]\n", PLATE)
    model = run(folder, "model", f"  - id: look\n    {explore}\n    actions: [model]\n", PLATE)
    return photos, model


def test_photograph_takes_photos_only_when_asked(photo_and_model) -> None:
    photos, model = photo_and_model
    asked, not_asked = element(photos, "look"), element(model, "look")
    assert asked["actions"]["photos"] == asked["views"] >= 5
    index = (photos.out / "photos" / "index.csv").read_text(encoding="utf-8").splitlines()
    assert len(index) == 1 + asked["actions"]["photos"]
    assert not_asked["views"] == 0 and "photos" not in not_asked["actions"]
    assert not (model.out / "photos").exists()
    assert not (photos.out / "stereo").exists()  # photographs are not a recording


def test_model_records_what_reconstruction_needs_and_names_the_folder(photo_and_model) -> None:
    _, model = photo_and_model
    look = element(model, "look")
    assert look["actions"]["model"] == "stereo/look"
    recording = read_stereo_recording(model.out / look["actions"]["model"])
    assert len(recording) == look["actions"]["recorded_pairs"] >= 0.8 * 2.0 * look["duration_s"]
    metrics = json.loads((model.out / "metrics.json").read_text(encoding="utf-8"))
    assert next(e for e in metrics["elements"] if e["id"] == "look")["actions"] == look["actions"]


def test_the_explore_sensor_is_the_one_flown_and_the_run_says_so(photo_and_model) -> None:
    photos, _ = photo_and_model
    assert element(photos, "look")["actions"]["sensor"] == "stereo"
    said = [e for e in read_events(photos.out / "events.jsonl") if e["event"] == "explore_sensor"]
    assert [(e["element"], e["sensor"]) for e in said] == [("look", "stereo")]
