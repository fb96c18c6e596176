"""Estimates before the dive (`mission.estimate`, `auv plan`, `auv validate --estimate`) against what the
simulator then does with the same mission."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from conftest import MISSIONS

from mission import load_mission, simulate
from mission.cli_plan import mission_estimate
from mission.estimate import estimate_mission, leg_time, vertical_time


def test_a_leg_takes_its_length_at_speed_plus_the_acceleration_and_the_slow_final_approach():
    fast = leg_time(1000.0, 1.5, 0.2, 3.0)
    assert 1000.0 / 1.5 + 3.75 < fast < 1000.0 / 1.5 + 3.75 + 60.0
    assert leg_time(1.0, 1.5, 0.2, 3.0) == 0.0  # already inside the capture circle
    assert leg_time(2000.0, 1.5, 0.2, 3.0) - fast == pytest.approx(1000.0 / 1.5)


def test_a_depth_change_takes_the_rate_limited_part_then_the_loops_tail():
    assert vertical_time(0.5, 0.5) == 0.0
    assert vertical_time(40.0, 0.5) - vertical_time(20.0, 0.5) == pytest.approx(40.0)


def test_the_transit_missions_estimate_is_within_10_percent_of_its_simulation_per_element():
    mission = load_mission(MISSIONS / "field_transit.yaml")
    estimate, dropped = mission_estimate(mission)  # charted from the mission's world, as `auv plan` does
    assert dropped == []
    run = simulate(mission, plots=False).metrics
    assert estimate.duration_s == pytest.approx(run["mission_time_s"], rel=0.1)
    assert estimate.energy_wh == pytest.approx(run["energy_wh"], rel=0.1)
    assert estimate.distance_m == pytest.approx(run["distance_m"], rel=0.1)
    for planned, flown in zip(estimate.elements, run["elements"], strict=True):
        assert planned.id == flown["id"]
        assert planned.duration_s == pytest.approx(flown["duration_s"], rel=0.1, abs=15.0), planned.id


def test_a_survey_is_estimated_from_its_own_plan_with_full_coverage():
    mission = load_mission(MISSIONS / "sps_field_inspection.yaml")
    survey = next(e for e in estimate_mission(mission).elements if e.kind == "survey")
    assert survey.basis == "plan" and survey.coverage_percent >= 99.0
    assert 2000.0 < survey.distance_m < 4000.0
    assert survey.duration_s == pytest.approx(survey.distance_m / mission.vehicle.cruise_speed, rel=0.05)


def test_auv_plan_prints_json_per_element_and_in_total_and_warns_past_max_duration():
    out = subprocess.run([sys.executable, "-m", "mission", "plan", str(MISSIONS / "duration_abort.yaml"), "--json"],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert {"id", "kind", "distance_m", "duration_s", "energy_wh", "basis"} <= set(data["elements"][0])
    assert data["total"]["duration_s"] == pytest.approx(sum(e["duration_s"] for e in data["elements"]), abs=0.5)
    assert any("exceeds max_duration" in w for w in data["warnings"])
