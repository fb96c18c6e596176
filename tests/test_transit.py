"""Transit missions simulated end to end, checked against the simulator's truth."""

import math

import numpy as np
import pytest

from mission import load_mission, simulate

LEGS = """
  - id: dive
    transit: {to: {north: 20, east: 20}, depth: 30}
  - id: east
    transit: {to: {north: 40, east: 350}, depth: 35}
  - id: north
    transit: {to: {north: 300, east: 300}, altitude: 12}
  - id: home
    transit: {to: home, depth: 0}
"""


def trajectory(result):
    rows = np.array([r[:14] for r in result.vehicle.log.rows], dtype=float)
    return {name: rows[:, k] for k, name in enumerate(
        ("time", "north", "east", "depth", "heading", "altitude", "north_est", "east_est", "depth_est",
         "heading_est", "altitude_est", "sigma", "speed", "energy"))}


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_waypoints_are_reached_within_the_capture_radius_in_true_position(write_mission, seed):
    result = simulate(load_mission(write_mission("legs", LEGS)), seed=seed)
    assert result.metrics["completed"]
    for element in result.metrics["elements"]:
        assert element["status"] == "succeeded"
        assert element["end_position_error_m"] <= 3.0, element
    t = trajectory(result)
    assert t["depth"][-1] < 1.0  # surfaced at home


def test_altitude_mode_holds_the_altitude_over_the_true_seabed(write_mission):
    result = simulate(load_mission(write_mission("legs", LEGS)), seed=4)
    t = trajectory(result)
    rows = np.array([e == "north" for e in (r[14] for r in result.vehicle.log.rows)])
    settled = rows & (t["time"] > t["time"][rows][0] + 60.0)
    assert np.abs(t["altitude"][settled] - 12.0).max() < 1.0


def test_estimate_error_stays_within_the_usbl_noise_while_fixes_arrive(write_mission):
    result = simulate(load_mission(write_mission("legs", LEGS)), seed=5)
    t = trajectory(result)
    err = np.hypot(t["north_est"] - t["north"], t["east_est"] - t["east"])
    converged = t["time"] > 60.0
    usbl_sigma = 1.5
    assert np.sqrt(np.mean(err[converged] ** 2)) < 0.5 * usbl_sigma
    assert err[converged].max() < usbl_sigma
    # The filter's own sigma is honest: the error rarely exceeds 3 sigma.
    assert np.mean(err[converged] > 3.0 * t["sigma"][converged]) < 0.01


@pytest.mark.parametrize("seed", [1, 2, 3, 4])
def test_dead_reckoning_drifts_at_the_configured_percentage_when_fixes_stop(write_mission, seed):
    route = """
  - id: out
    transit: {to: {north: 340, east: 440}, depth: 30, navigation: dead-reckoning}
"""
    extra = "vehicle: {cruise_speed: 1.5}\n"
    header_drift = 0.8
    path = write_mission("dr", route, extra)
    path.write_text(path.read_text().replace("drift_percent: 0.5", f"drift_percent: {header_drift}"))
    result = simulate(load_mission(path), seed=seed)
    t = trajectory(result)
    distance = result.metrics["distance_m"]
    drift = math.hypot(t["north_est"][-1] - t["north"][-1], t["east_est"][-1] - t["east"][-1])
    assert result.metrics["navigation"]["usbl_fixes"] == 0
    assert drift / distance * 100.0 == pytest.approx(header_drift, rel=0.2)
    assert t["sigma"][-1] == pytest.approx(1.5 + header_drift / 100.0 * distance, rel=0.1)


def test_a_leg_over_the_geofence_aborts_home_and_surfaces(write_mission):
    route = """
  - id: dive
    transit: {to: {north: 50, east: 400}, depth: 25}
  - id: stray
    transit: {to: {north: 300, east: 100}, depth: 25}
  - id: skipped
    transit: {to: {north: 200, east: 50}, depth: 25}
"""
    path = write_mission("fence", route)
    text = path.read_text().replace("geofence: [[-60, -60], [-60, 460], [360, 460], [360, -60]]",
                                    "geofence: [[-60, -60], [-60, 460], [100, 460], [100, 150], [360, 150], "
                                    "[360, -60]]")
    path.write_text(text)
    result = simulate(load_mission(path), seed=2)
    m = result.metrics
    assert m["aborted"] and not m["completed"]
    assert [v["monitor"] for v in m["safety_violations"]] == ["geofence"]
    v = m["safety_violations"][0]
    assert v["element"] == "stray" and v["north"] == pytest.approx(100.0, abs=3.0)
    statuses = {e["id"]: e["status"] for e in m["elements"]}
    assert statuses == {"dive": "succeeded", "stray": "aborted", "skipped": "skipped",
                        "abort-return": "succeeded", "abort-surface": "succeeded"}
    t = trajectory(result)
    assert math.hypot(t["north"][-1], t["east"][-1]) <= 3.0 and t["depth"][-1] < 1.0


def test_max_depth_in_altitude_mode_over_deep_seabed_aborts(write_mission):
    route = """
  - id: hug
    transit: {to: {north: 200, east: 200}, altitude: 3}
"""
    path = write_mission("deep", route)
    path.write_text(path.read_text().replace("max_depth: 120", "max_depth: 50"))
    result = simulate(load_mission(path), seed=1)
    assert [v["monitor"] for v in result.metrics["safety_violations"]] == ["max_depth"]
    assert result.metrics["aborted"]


def test_running_out_of_energy_reserve_aborts(write_mission):
    route = """
  - id: long
    transit: {to: {north: 300, east: 400}, depth: 20}
"""
    path = write_mission("energy", route, "vehicle: {energy_wh: 20}\n")
    result = simulate(load_mission(path), seed=1)
    m = result.metrics
    assert [v["monitor"] for v in m["safety_violations"]] == ["energy_reserve"]
    assert m["elements"][0]["status"] == "aborted"


def test_an_element_past_its_timeout_fails_and_can_abort_the_mission(write_mission):
    route = """
  - id: slow
    transit: {to: {north: 300, east: 400}, depth: 20}
    timeout: 30s
    on_failure: abort
  - id: after
    transit: {to: {north: 0, east: 50}, depth: 20}
"""
    result = simulate(load_mission(write_mission("timeout", route)), seed=1)
    m = result.metrics
    assert m["elements"][0]["status"] == "timeout"
    assert m["elements"][0]["duration_s"] == pytest.approx(30.0, abs=0.5)
    assert m["elements"][1]["status"] == "skipped"
    assert m["aborted"] and "slow" in m["abort_reason"]


def test_a_mission_past_its_max_duration_aborts(write_mission):
    route = """
  - id: long
    transit: {to: {north: 300, east: 400}, depth: 20}
"""
    path = write_mission("duration", route)
    path.write_text(path.read_text().replace("min_altitude: 1.5", "min_altitude: 1.5\n  max_duration: 2min"))
    m = simulate(load_mission(path), seed=1).metrics
    assert [v["monitor"] for v in m["safety_violations"]] == ["max_duration"]
    assert m["safety_violations"][0]["time"] == pytest.approx(120.0, abs=0.5)
    assert m["aborted"]
