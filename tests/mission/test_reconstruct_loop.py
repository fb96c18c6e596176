"""`mission.reconstruct_loop`: a follow-up mission's photographs measured against the named targets' true positions
(the true camera against the viewpoint placed on the true target), and its referencing attempts counted per set."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from mission.frames import camera_pose
from mission.reconstruct_loop import photo_errors, recognitions

ENTRY = {"id": "w", "pose": {"north": 10.0, "east": 20.0, "depth": 30.0, "heading": 0.0},
         "targets": [{"id": "cap", "at": [1.0, 2.0, -3.0], "reference": "s", "standoff": 2.5}]}
TRUE_CAP = np.array([11.2, 21.9, 27.0])  # the entry frame is 0.2 m north, 0.1 m west of the truth here


def _run(tmp_path: Path, camera_world: np.ndarray, heading: float) -> Path:
    """A run folder with one photograph of `cap` taken with the left camera at `camera_world`."""
    # The left camera sits half a baseline from the vehicle's centre (camera_pose's mount): place the vehicle so.
    offset = camera_pose(0.0, 0.0, 0.0, heading, baseline=0.25)[:3, 3]
    body = camera_world - offset
    rows = ["time,north,east,depth,heading", f"4.8,{body[0] + 1},{body[1]},{body[2]},{heading}",
            f"5.0,{body[0]},{body[1]},{body[2]},{heading}"]
    (tmp_path / "trajectory.csv").write_text("\n".join(rows) + "\n")
    viewpoint = [1.0, 2.0, -5.5]  # 2.5 m above the target in the entry frame
    photo = {"target": "cap", "time": 5.0, "viewpoint_object": viewpoint}
    attempts = [{"stage": "search", "set": "s", "recognised": False},
                {"stage": "fine", "set": "s", "recognised": True, "recognised_set": "s", "ambiguous": False},
                {"stage": "fused", "set": "s", "recognised": True, "recognised_set": "s"},
                {"stage": "fine", "set": "s", "recognised": True, "recognised_set": "s", "ambiguous": True}]
    metrics = {"elements": [{"id": "look", "photos": [photo], "attempts": attempts}]}
    (tmp_path / "metrics.json").write_text(json.dumps(metrics))
    return tmp_path


def test_a_camera_above_the_true_target_at_the_standoff_has_no_error(tmp_path: Path) -> None:
    run = _run(tmp_path, TRUE_CAP + [0.0, 0.0, -2.5], heading=37.0)
    [row] = photo_errors(run, "look", ENTRY, {"cap": TRUE_CAP.tolist()}, 0.25)
    assert row["error_m"] == pytest.approx(0.0, abs=1e-3)
    assert row["target_off_axis"] == pytest.approx(0.0, abs=1e-3)


def test_a_camera_above_where_the_entry_puts_the_target_is_off_by_the_entry_s_error(tmp_path: Path) -> None:
    entry_cap = np.array([11.0, 22.0, 27.0])  # origin + at: the entry's idea of the target, 0.22 m off the truth
    run = _run(tmp_path, entry_cap + [0.0, 0.0, -2.5], heading=200.0)
    [row] = photo_errors(run, "look", ENTRY, {"cap": TRUE_CAP.tolist()}, 0.25)
    assert row["error_m"] == pytest.approx(float(np.hypot(0.2, 0.1)), abs=1e-3)


def test_recognitions_count_unambiguous_identifications_and_leave_fused_records_out(tmp_path: Path) -> None:
    run = _run(tmp_path, TRUE_CAP, heading=0.0)
    assert recognitions(run, "look") == {"s": {"recognised": 1, "attempts": 3}}
