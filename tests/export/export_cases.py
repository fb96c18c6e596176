"""A small mission placed on the globe and a synthetic run folder of it, for the export tests (plain functions:
a `conftest.py` here would shadow `tests/conftest.py`, which other tests import as `conftest`)."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import yaml

from mission.runfolder import TRAJECTORY_COLUMNS

ORIGIN = {"lat": 42.95, "lon": 131.85}
# A survey ~13 km out from the origin, a geofence 10 km across, a transit there and back.
MISSION = {
    "name": "far-survey",
    "origin": ORIGIN,
    "sensors": {"mbes": {"swath_deg": 120}, "usbl": {}, "scanner": {}},
    "safety": {"geofence": [[-100, -100], [-100, 10000], [10000, 10000], [10000, -100]], "max_depth": 200},
    "objects": [{"id": "manifold-1", "pose": {"north": 9150, "east": 9200, "depth": 58, "heading": 30},
                 "size": [8, 5, 2.5]}],
    "route": [
        {"id": "out", "transit": {"to": {"north": 9000, "east": 9000}, "depth": 40, "capture_radius": 4}},
        {"id": "far-field", "survey": {"area": [[9000, 9000], [9000, 9400], [9300, 9400], [9300, 9000]],
                                       "exclude": [[[9060, 9300], [9060, 9340], [9095, 9340], [9095, 9300]]],
                                       "altitude": 20, "speed": 1.2}},
        {"id": "back", "transit": {"to": "home", "depth": 0}},
    ],
}
ADAPTIVE = {**MISSION, "name": "with-inspect",
            "route": [*MISSION["route"][:2], {"id": "look-closer", "explore": {"object": "manifold-1"}},
                      MISSION["route"][2]]}


def write_mission(path: Path, mission: dict[str, object]) -> Path:
    path.write_text(yaml.safe_dump(mission, sort_keys=False), encoding="utf-8")
    return path


def far_mission(tmp_path: Path) -> Path:
    return write_mission(tmp_path / "far.yaml", MISSION)


def synthetic_run(tmp_path: Path) -> Path:
    """A run folder as `auv simulate` leaves it: 120 trajectory rows, a photo, a safety event, a survey map."""
    run = tmp_path / "run"
    run.mkdir()
    write_mission(run / "mission.yaml", MISSION)
    t = np.arange(120) * 0.5
    north, east = 9000 + 2.0 * t, 9000 + 1.0 * t
    with (run / "trajectory.csv").open("w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(TRAJECTORY_COLUMNS)
        for k in range(len(t)):
            w.writerow([t[k], north[k], east[k], 40.0, 63.4, 18.0, north[k] + 0.3, east[k] - 0.2, 40.1, 63.0, 18.1,
                        0.5, 1.2, 0.1 * k, "far-field"])
    events = [{"time": 0.0, "event": "element_started", "element": "far-field", "kind": "survey"},
              {"time": 20.0, "event": "photo", "element": "far-field", "target": "t1", "file": "photos/t1_0.png"},
              {"time": 40.0, "event": "safety_violation", "monitor": "geofence", "element": "far-field"},
              {"time": 59.5, "event": "element_failed", "element": "far-field", "kind": "survey", "reason": "x"}]
    (run / "events.jsonl").write_text("".join(json.dumps(e) + "\n" for e in events), encoding="utf-8")
    detections = [{"id": "manifold-1", "north": 9152.0, "east": 9201.0, "height": float("nan")}]
    metrics = {"completed": False, "elements": [{"id": "far-field", "detections": detections}]}
    (run / "metrics.json").write_text(json.dumps(metrics), encoding="utf-8")  # NaN, as json writes it
    (run / "maps").mkdir()
    depth = np.full((4, 5), 60.0)
    depth[0, 0] = np.nan
    np.savez_compressed(run / "maps" / "far-field.npz", depth=depth, info=np.ones((4, 5)), north0=np.array(9000.0),
                        east0=np.array(9000.0), cell=np.array(0.5), lines=np.zeros((0, 2, 2)))
    occupied = np.array([[9150.0, 9200.0, 57.0, 0.0], [9150.1, 9200.0, 57.0, 0.0], [9150.2, 9200.1, 56.9, 0.0]])
    np.savez_compressed(run / "maps" / "look-closer.npz", explore_occupied=occupied, lines=np.zeros((0, 2, 2)))
    return run


def adaptive_mission(tmp_path: Path) -> Path:
    return write_mission(tmp_path / "adaptive.yaml", ADAPTIVE)


def no_origin_mission(tmp_path: Path) -> Path:
    return write_mission(tmp_path / "no_origin.yaml", {k: v for k, v in MISSION.items() if k != "origin"})
