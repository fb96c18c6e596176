"""`auv simulate --seeds`: many seeded runs of one mission, each a full run folder, and the campaign summary."""

import json

import pytest
from conftest import MISSIONS

from mission.cli import main
from mission.errors import AuvError
from mission.sim.campaign import aggregate, parse_seeds


def test_seed_lists_and_ranges():
    assert parse_seeds("1-4") == [1, 2, 3, 4]
    assert parse_seeds("7, 3,3-5") == [7, 3, 4, 5]
    for bad in ("", "a", "5-2", "1-"):
        with pytest.raises(AuvError):
            parse_seeds(bad)


def _row(seed, completed, inspect_status="succeeded", camera=0.04, error=None):
    if error:
        return {"seed": seed, "error": error}
    return {"seed": seed, "completed": completed, "aborted": False, "safety_violations": 0, "seabed_contacts": 0,
            "elements": {"survey": {"kind": "survey", "status": "succeeded", "coverage_percent": 99.6 - seed},
                         "look": {"kind": "inspect", "status": inspect_status, "targets_ok": 4 if completed else 2,
                                  "camera_error_max_m": camera, "min_altitude_m": 2.0 - seed / 10}}}


def test_aggregate_counts_outcomes_and_keeps_the_worst_figures():
    s = aggregate([_row(1, True), _row(2, False, "failed", 0.07), _row(3, True, camera=0.02),
                   _row(4, False, error="RuntimeError: boom")])
    assert (s["runs"], s["completed"], s["crashed"], s["completed_percent"]) == (4, 2, 1, 50.0)
    assert s["failed_seeds"] == [2, 4]
    look = s["elements"]["look"]
    assert (look["runs"], look["succeeded"]) == (3, 2)
    assert look["worst_camera_error_max_m"] == 0.07 and look["worst_targets_ok"] == 2
    assert look["worst_min_altitude_m"] == pytest.approx(1.7)
    assert s["elements"]["survey"]["worst_coverage_percent"] == pytest.approx(96.6)


def test_seeded_runs_in_parallel_write_their_folders_and_the_summary(tmp_path, capsys):
    out = tmp_path / "campaign"
    code = main(["simulate", str(MISSIONS / "field_transit.yaml"), "--seeds", "3-4", "--jobs", "2", "--out",
                 str(out), "--no-plots"])
    text = capsys.readouterr().out
    assert code == 0 and "completed 2/2" in text
    report = json.loads((out / "campaign.json").read_text())
    assert [r["seed"] for r in report["runs"]] == [3, 4]
    for seed in (3, 4):
        metrics = json.loads((out / f"seed-{seed}" / "metrics.json").read_text())
        assert metrics["seed"] == seed and metrics["completed"]
        row = next(r for r in report["runs"] if r["seed"] == seed)
        assert row["mission_time_s"] == metrics["mission_time_s"]  # the row is that run's own metrics
    assert report["summary"]["completed_percent"] == 100.0
    a, b = ((out / f"seed-{s}" / "trajectory.csv").read_text() for s in (3, 4))
    assert a != b  # the seeds really differ


def test_seeds_refuses_a_single_seed_too(tmp_path, capsys):
    code = main(["simulate", str(MISSIONS / "field_transit.yaml"), "--seeds", "1-2", "--seed", "3", "--out",
                 str(tmp_path / "x")])
    assert code != 0 and "--seeds" in capsys.readouterr().err


def test_a_killed_run_is_recorded_as_incomplete_and_the_campaign_ends_without_a_traceback(tmp_path):
    import os
    import signal
    import subprocess
    import sys
    import time

    from conftest import WORLD

    legs = "".join(f"\n  - {{id: leg{k}, transit: {{to: {{north: {250 * (k % 2)}, east: 0}}, depth: 30}}}}"
                   for k in range(20))  # ~3,400 s simulated: a few seconds
    mission = tmp_path / "long.yaml"
    mission.write_text(f"name: long\nworld: {WORLD}\nsensors: {{usbl: {{sigma: 1.5}}}}\n"
                       f"safety: {{max_duration: 20h}}\nvehicle: {{energy_wh: 100000}}\nroute:{legs}\n")
    out = tmp_path / "campaign"
    proc = subprocess.Popen([sys.executable, "-m", "mission", "simulate", str(mission), "--seeds", "1-2", "--jobs",
                             "2", "--no-plots", "--out", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    marker = out / "seed-1" / ".auv-run"
    deadline = time.monotonic() + 90
    while time.monotonic() < deadline and not (marker.is_file() and marker.read_text().strip()):
        time.sleep(0.05)
    os.kill(json.loads(marker.read_text())["pid"], signal.SIGKILL)  # the worker running seed 1
    stdout, stderr = proc.communicate(timeout=90)
    assert proc.returncode == 1 and "Traceback" not in stderr, stderr
    report = json.loads((out / "campaign.json").read_text())
    row = next(r for r in report["runs"] if r["seed"] == 1)
    assert row["error"].startswith("the run's process died") and row["error"].endswith("seed-1 is incomplete")
    assert "CRASHED" in stdout and report["summary"]["crashed"] >= 1
