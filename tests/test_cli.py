"""The `auv` command: exit codes, one-line refusals, the run folder contract, and simulation speed."""

import csv
import json
import subprocess
import sys

from conftest import MISSIONS

from mission.cli import main
from mission.sim.vehicle import TRAJECTORY_COLUMNS

METRIC_KEYS = {"mission", "seed", "completed", "mission_time_s", "wall_time_s", "distance_m", "energy_wh",
               "elements", "safety_violations", "navigation"}


def test_simulate_writes_the_run_folder_contract(tmp_path, capsys):
    out = tmp_path / "run"
    code = main(["simulate", str(MISSIONS / "field_transit.yaml"), "--out", str(out), "--seed", "5", "-q"])
    assert code == 0
    assert "field-transit: completed" in capsys.readouterr().out
    metrics = json.loads((out / "metrics.json").read_text())
    assert METRIC_KEYS <= set(metrics)
    assert metrics["seed"] == 5
    assert {"position_error_rms_m", "position_error_max_m"} <= set(metrics["navigation"])
    assert all({"id", "kind", "status", "duration_s"} <= set(e) for e in metrics["elements"])
    with (out / "trajectory.csv").open() as f:
        rows = list(csv.reader(f))
    assert tuple(rows[0]) == TRAJECTORY_COLUMNS and len(rows) > 100
    events = [json.loads(line) for line in (out / "events.jsonl").read_text().splitlines()]
    assert events[0]["event"] == "mission_started" and events[-1]["event"] == "mission_finished"


def test_same_seed_same_run_other_seed_other_run(tmp_path):
    for name, seed in (("a", 1), ("b", 1), ("c", 2)):
        main(["simulate", str(MISSIONS / "field_transit.yaml"), "--out", str(tmp_path / name), "--seed",
              str(seed), "--no-plots", "-q"])
    a, b, c = ((tmp_path / n / "trajectory.csv").read_text() for n in "abc")
    assert a == b and a != c


def test_simulate_refuses_unsupported_kinds_in_one_line(write_mission, tmp_path, capsys, monkeypatch):
    from mission.agents import REGISTRY

    monkeypatch.delitem(REGISTRY, "explore")  # every kind has an agent now: pretend this one has none
    route = """
  - id: go
    transit: {to: {north: 30, east: 30}, depth: 10}
  - id: look
    explore: {object: detected, sensor: scanner}
"""
    path = write_mission("unsupported", route)
    path.write_text(path.read_text().replace("usbl: {sigma: 1.5, rate_hz: 0.5}",
                                             "usbl: {sigma: 1.5, rate_hz: 0.5}\n  scanner: {max_range: 10}"))
    assert main(["validate", str(path)]) == 0
    code = main(["simulate", str(path), "--out", str(tmp_path / "run")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1
    assert len(err) == 1 and "explore" in err[0] and "look" in err[0] and "Traceback" not in err[0]
    assert not (tmp_path / "run").exists()


def test_schema_and_plugins_commands(capsys):
    assert main(["schema"]) == 0
    schema = json.loads(capsys.readouterr().out)
    assert schema["title"].startswith("auv-mission") and "route" in schema["required"]
    assert main(["plugins"]) == 0
    assert "stereo-referencing       perception_plugins.referencing.plugin:StereoReferencingPlugin" in \
        capsys.readouterr().out


def test_python_dash_m_mission_is_the_auv_command():
    run = subprocess.run([sys.executable, "-m", "mission", "validate", str(MISSIONS / "field_transit.yaml")],
                         capture_output=True, text=True, check=False)
    assert run.returncode == 0 and "ok" in run.stdout


def test_a_one_hour_transit_mission_simulates_at_720x_real_time_or_faster(tmp_path):
    from mission import load_mission, simulate

    result = simulate(load_mission(MISSIONS / "transit_hour.yaml"), out=tmp_path / "run", plots=False)
    m = result.metrics
    assert m["completed"] and m["mission_time_s"] >= 3600
    assert m["wall_time_s"] <= 5.0
    assert m["realtime_factor"] >= 720
