"""Faults injected from the mission (`faults:`): each acts on the simulated vehicle in its window, shows in the events,
and is measured here against the truth the simulator keeps."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from conftest import WORLD

from mission import simulate
from mission.cli import main
from mission.language import load_mission, validate_mission_file
from mission.sim.run import RunResult

BOX = """
  - id: dive
    transit: {to: {north: 0, east: 0}, depth: 30}
  - id: north-leg
    transit: {to: {north: 250, east: 0}, depth: 30}
  - id: east-leg
    transit: {to: {north: 250, east: 350}, depth: 30}
  - id: home
    transit: {to: home, depth: 0}
"""


DR_BOX = BOX.replace("depth: 30}", "depth: 30, navigation: dead-reckoning}").replace(
    "depth: 0}", "depth: 0, navigation: dead-reckoning}")


def header(usbl: bool = True, drift: float = 0.5) -> str:
    return f"""
world: {WORLD}
seed: 3
sensors:
  {"usbl: {sigma: 1.5, rate_hz: 0.5}" if usbl else ""}
  dvl: {{drift_percent: {drift}}}
safety:
  geofence: [[-60, -60], [-60, 460], [360, 460], [360, -60]]
  max_depth: 120
  min_altitude: 1.5
  energy_reserve: 20%
  on_violation: {{abort_to: home}}
"""


def run(write_mission, faults: str, usbl: bool = True, drift: float = 0.5, route: str = BOX) -> RunResult:
    path = write_mission("faulty", route, f"faults:\n{faults}", header=header(usbl, drift))
    return simulate(load_mission(path), plots=False)


def track(result: RunResult) -> dict[str, np.ndarray]:
    rows = np.array([r[:14] for r in result.vehicle.log.rows], dtype=float)
    names = ("time", "north", "east", "depth", "heading", "altitude", "north_est", "east_est", "depth_est",
             "heading_est", "altitude_est", "sigma", "speed", "energy")
    out = {n: rows[:, k] for k, n in enumerate(names)}
    out["error"] = np.hypot(out["north"] - out["north_est"], out["east"] - out["east_est"])
    return out


def between(t: dict[str, np.ndarray], a: float, b: float) -> np.ndarray:
    return (t["time"] >= a) & (t["time"] < b)


def test_during_a_usbl_outage_no_fix_is_used_the_estimate_drifts_and_comes_back_after(write_mission):
    result = run(write_mission, "  - usbl_outage: {start: 60s, end: 300s}", drift=2.0)
    fixes = [f.time for f in result.vehicle.log.fixes]
    assert not [t for t in fixes if 60.0 - 1e-6 <= t < 300.0 - 1e-6]
    assert len([t for t in fixes if t >= 300.0]) > 20  # the fixes come back
    t = track(result)
    before, late, after = between(t, 30, 60), between(t, 280, 300), between(t, 340, 380)
    # 2 % DVL drift over ~350 m flown blind: metres of true error, where the aided estimate was within ~1.5 m
    assert t["error"][late].mean() > 3.0 > t["error"][before].mean()
    assert t["sigma"][late].max() > 3.0 * t["sigma"][before].max()
    assert t["error"][after].mean() < 0.5 * t["error"][late].mean()
    assert result.metrics["completed"]


def test_a_dvl_dropout_is_seen_by_the_navigation_and_the_current_carries_the_estimate_off(write_mission):
    result = run(write_mission, "  - dvl_dropout: {start: 100s, end: 220s}", usbl=False, route=DR_BOX)
    t = track(result)
    window, before = between(t, 100.5, 219.5), between(t, 40, 100)
    assert np.isnan(t["altitude_est"][window]).all()  # the DVL's altitude went with it
    assert not np.isnan(t["altitude_est"][before]).any()
    # without bottom track the filter grows at 0.1 m/s: 120 s add ~12 m of sigma (the DVL alone adds < 1 m)
    grown = t["sigma"][window][-1] - t["sigma"][window][0]
    assert grown > 10.0
    # the unknown current (0.13 m/s in this world) moves the truth away from the estimate: ~15 m in 120 s
    assert t["error"][window][-1] > 8.0 > t["error"][before].max()
    # the true error stays within the filter's own 3 sigma: it knows it is lost
    assert t["error"][window][-1] < 3.0 * t["sigma"][window][-1]


def test_a_degraded_thruster_caps_the_true_speed_in_its_window_only(write_mission):
    result = run(write_mission, "  - thruster_degraded: {start: 80s, end: 200s, fraction: 0.4}")
    t = track(result)
    # max_speed 2.0 m/s by default; from cruise (1.5 m/s) it slows at the degraded deceleration (0.08 m/s²): ~9 s
    assert t["speed"][between(t, 90, 199.5)].max() <= 0.4 * 2.0 + 1e-6
    assert t["speed"][between(t, 70, 80)].min() == pytest.approx(1.5, abs=0.01)
    assert t["speed"][between(t, 200, 400)].max() == pytest.approx(1.5, abs=0.01)  # cruise again
    assert result.metrics["completed"]


def test_a_battery_step_trips_the_energy_reserve_and_the_vehicle_goes_home_and_surfaces(write_mission):
    result = run(write_mission, "  - battery_step: {start: 100s, percent: 80}")
    m = result.metrics
    assert m["aborted"] and not m["completed"]
    monitors = [v["monitor"] for v in m["safety_violations"]]
    assert monitors == ["energy_reserve"]
    assert m["safety_violations"][0]["time"] == pytest.approx(100.0, abs=0.5)
    t = track(result)
    assert t["energy"][between(t, 100.1, 101)].min() >= 0.8 * 4000.0  # the step is in the energy used
    assert t["depth"][-1] < 1.0 and math.hypot(t["north"][-1], t["east"][-1]) < 5.0  # home, at the surface


def test_fault_events_mark_each_window_in_the_event_log(write_mission, tmp_path):
    path = write_mission("faulty", BOX, "faults:\n  - usbl_outage: {start: 10, end: 20}\n"
                         "  - thruster_degraded: {start: 30, fraction: 0.9}\n", header=header())
    simulate(load_mission(path), out=tmp_path / "run", plots=False)
    lines = (tmp_path / "run" / "events.jsonl").read_text().splitlines()
    faults = [ln for ln in lines if '"fault_' in ln]
    assert len(faults) == 3
    assert '"time": 10.0, "event": "fault_started", "fault": "usbl_outage"' in faults[0]
    assert '"time": 20.0, "event": "fault_ended", "fault": "usbl_outage"' in faults[1]
    assert '"fault_started", "fault": "thruster_degraded"' in faults[2] and '"fraction": 0.9' in faults[2]


def test_a_lost_multibeam_delivers_nothing_and_a_frozen_one_repeats_its_last_ping(write_mission):
    from mission.sim.vehicle import SimulatedVehicle
    from mission.vehicle import Command
    from mission.world.scene import build_scene

    path = write_mission("sonar", DR_BOX, "sensors:\n  mbes: {beams: 32, rate_hz: 5}\n  dvl: {drift_percent: 0.5}\n"
                         "faults:\n  - sensor_lost: {start: 2, end: 4, sensor: multibeam}\n"
                         "  - sensor_frozen: {start: 4, end: 6, sensor: multibeam}\n",
                         header=f"world: {WORLD}\nsafety: {{max_depth: 120}}\n")
    mission = load_mission(path)
    from mission.language.loader import load_world

    vehicle = SimulatedVehicle(mission, build_scene(load_world(mission.world)), seed=1)
    vehicle.set_payload(frozenset({"mbes"}))
    vehicle.apply(Command(heading=45.0, speed=1.5, depth=30.0))
    pings: list[tuple[float, np.ndarray]] = []
    while vehicle.truth.time < 8.0:
        vehicle.advance()
        pings += [(p.time, p.ranges.copy()) for p in vehicle.observe().sonar]
    times = [t for t, _ in pings]
    assert not [t for t in times if 2.0 <= t < 4.0 - 1e-9]  # lost: nothing
    frozen = [r for t, r in pings if 4.0 + 1e-9 < t < 6.0 - 1e-9]
    last_before = [r for t, r in pings if t < 2.0][-1]
    assert len(frozen) >= 8 and all(np.array_equal(r, last_before) for r in frozen)  # frozen: the same data
    live = [r for t, r in pings if t > 6.2]
    assert len(live) >= 8 and not np.array_equal(live[0], live[-1])  # live again: the seabed changes under it


def test_bad_fault_entries_are_located(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(f"""name: bad
world: {WORLD}
route:
  - id: a
    transit: {{to: home}}
faults:
  - usbl_outage: {{start: 100, end: 50}}
  - sensor_lost: {{start: 1, sensor: sonar}}
  - battery_step: {{start: 5}}
  - thruster_degraded: {{fraction: 1.5}}
  - engine_fire: {{start: 1}}
""", encoding="utf-8")
    mission, diags = validate_mission_file(path)
    assert mission is None
    lines = {d.line for d in diags if not d.warning}
    assert {7, 8, 9, 10, 11} <= lines, [str(d) for d in diags]


def test_auv_run_refuses_a_mission_with_faults_on_the_line_of_its_faults_key(write_mission, capsys):
    path = write_mission("faulty", BOX, "faults:\n  - usbl_outage: {start: 10, end: 20}\n", header=header())
    assert main(["run", str(path), "--vehicle", "mavlink:udpin:127.0.0.1:14999", "--out",
                 str(Path(path).parent / "run")]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    line = next(k for k, text in enumerate(path.read_text().splitlines(), 1) if text.startswith("faults:"))
    assert len(err) == 1 and err[0].startswith(f"{path}:{line}:1: faults: inject faults in simulation only")
    assert not (Path(path).parent / "run").exists()


def test_a_multibeam_switched_back_on_pings_at_its_rate_with_no_burst_of_missed_pings(write_mission):
    from mission.language.loader import load_world
    from mission.sim.vehicle import SimulatedVehicle
    from mission.vehicle import Command
    from mission.world.scene import build_scene

    path = write_mission("sonar", DR_BOX, "sensors:\n  mbes: {beams: 32, rate_hz: 5}\n  dvl: {drift_percent: 0.5}\n",
                         header=f"world: {WORLD}\nsafety: {{max_depth: 120}}\n")
    mission = load_mission(path)
    vehicle = SimulatedVehicle(mission, build_scene(load_world(mission.world)), seed=1)
    vehicle.apply(Command(heading=45.0, speed=1.5, depth=30.0))
    times: list[float] = []
    for payload, until in ((frozenset({"mbes"}), 2.0), (frozenset(), 12.0), (frozenset({"mbes"}), 14.0)):
        vehicle.set_payload(payload)
        while vehicle.truth.time < until - 1e-9:
            vehicle.advance()
            times += [p.time for p in vehicle.observe().sonar]
    after = [t for t in times if t > 12.0 - 1e-9]
    assert not [t for t in times if 2.2 < t < 12.0 - 1e-9]  # off: nothing
    assert 9 <= len(after) <= 11  # 2 s at 5 Hz, not the 50 pings that fell due while it was off
