"""`auv run` flies missions over MAVLink against `auv sim serve`, both started as a user starts them (two processes,
real UDP on loopback), and `auv score` scores the run against the truth the simulator kept."""

from __future__ import annotations

import json
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("mujoco")

ROOT = Path(__file__).resolve().parents[2]
AUV = [sys.executable, "-m", "mission"]
SPEEDUP = 30

# field_transit's first three legs (depth, USBL, altitude-following over the manifold) and home, shortened.
SHORT_TRANSIT = """\
name: short-transit
origin: {lat: 42.95, lon: 131.85}
world: WORLD
seed: 7
sensors:
  usbl: {sigma: 1.5, rate_hz: 0.5}
  dvl:  {drift_percent: 0.5}
safety:
  geofence: [[-60, -60], [-60, 460], [360, 460], [360, -60]]
  max_depth: 120
  min_altitude: 1.5
  max_duration: 1h
  on_violation: {abort_to: home}
route:
  - id: dive
    transit: {to: {north: 0, east: 0}, depth: 20, navigation: usbl}
  - id: to-manifold
    transit: {to: {north: 110, east: 150}, altitude: 8, navigation: usbl}
  - id: back-dr
    transit: {to: {north: 40, east: 40}, depth: 20, navigation: dead-reckoning}
  - id: home
    transit: {to: home, depth: 0}
"""


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def serve(mission: Path, port: int, truth: Path) -> subprocess.Popen[str]:
    return subprocess.Popen([*AUV, "sim", "serve", str(mission), "--mavlink", f"udpout:127.0.0.1:{port}",
                             "--speedup", str(SPEEDUP), "--out", str(truth), "-q"], cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


def run(mission: Path, port: int, out: Path) -> subprocess.Popen[str]:
    return subprocess.Popen([*AUV, "run", str(mission), "--vehicle", f"mavlink:udpin:127.0.0.1:{port}",
                             "--out", str(out)], cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True)


def fly(mission: Path, tmp_path: Path, timeout: float = 240.0) -> tuple[int, str, Path, Path]:
    port = free_udp_port()
    truth, out = tmp_path / "truth", tmp_path / "run"
    server = serve(mission, port, truth)
    try:
        runner = run(mission, port, out)
        output, _ = runner.communicate(timeout=timeout)
    finally:
        server.send_signal(signal.SIGTERM)
        server.communicate(timeout=20)
    return runner.returncode, output, out, truth


def events(folder: Path) -> list[dict]:
    return [json.loads(line) for line in (folder / "events.jsonl").read_text().splitlines()]


def simulated(mission: Path, tmp_path: Path) -> dict:
    from mission import load_mission, simulate

    return simulate(load_mission(mission), out=tmp_path / "sim", plots=False).metrics


def test_a_transit_mission_flies_over_mavlink_and_scores_like_the_simulation(tmp_path):
    mission = tmp_path / "short_transit.yaml"
    mission.write_text(SHORT_TRANSIT.replace("WORLD", str(ROOT / "worlds" / "sps_field.yaml")))
    code, output, out, truth = fly(mission, tmp_path)
    assert code == 0, output
    scored = subprocess.run([*AUV, "score", str(out), "--truth", str(truth)], cwd=ROOT, capture_output=True,
                            text=True, timeout=60)
    assert scored.returncode == 0, scored.stderr
    flown = json.loads((out / "metrics.json").read_text())
    offline = simulated(mission, tmp_path)
    assert flown["completed"] and flown["scored"]
    assert [e["status"] for e in flown["elements"]] == ["succeeded"] * 4
    # the same navigation errors as the simulation of the same seed, within 1.5× (plus the filter's noise floor)
    nav, ref = flown["navigation"], offline["navigation"]
    assert nav["position_error_rms_m"] <= 1.5 * ref["position_error_rms_m"] + 0.1, (nav, ref)
    assert set(offline) <= set(flown)
    for a, b in zip(flown["elements"], offline["elements"], strict=True):
        assert set(b) <= set(a), (a["id"], set(b) - set(a))
        assert a["end_position_error_m"] < 5.0  # the true end of each leg is near its goal
    over = next(e for e in flown["elements"] if e["id"] == "to-manifold")
    assert 5.0 < over["min_altitude_m"] < 11.0  # altitude-following held over the seabed and the manifold
    assert {e["event"] for e in events(tmp_path / "sim")} <= {e["event"] for e in events(out)}
    times = [float(line.split(",")[0]) for line in (out / "trajectory.csv").read_text().splitlines()[1:]]
    assert abs(times[-1] - times[0] - flown["mission_time_s"]) < 1.0  # the vehicle's clock, not the host's
    assert flown["wall_time_s"] < flown["mission_time_s"] / (SPEEDUP / 3)


@pytest.mark.parametrize("name", ["duration_abort.yaml", "geofence_abort.yaml"])
def test_abort_missions_abort_over_mavlink_as_in_simulation(name, tmp_path):
    mission = ROOT / "missions" / name
    code, output, out, _ = fly(mission, tmp_path)
    assert code == 1, output
    flown = json.loads((out / "metrics.json").read_text())
    offline = simulated(mission, tmp_path)
    assert flown["aborted"] and not flown["completed"]
    assert [(e["id"], e["status"]) for e in flown["elements"]] == [(e["id"], e["status"])
                                                                  for e in offline["elements"]]
    assert [v["monitor"] for v in flown["safety_violations"]][:1] == [v["monitor"] for v in
                                                                      offline["safety_violations"]][:1]


def test_killing_the_vehicle_mid_run_gives_link_lost_within_the_timeout_and_a_complete_run_folder(tmp_path):
    mission = ROOT / "missions" / "field_transit.yaml"
    port = free_udp_port()
    server = serve(mission, port, tmp_path / "truth")
    runner = run(mission, port, tmp_path / "run")
    try:
        deadline = time.monotonic() + 60
        trajectory = tmp_path / "run" / "trajectory.csv"
        while time.monotonic() < deadline and (not trajectory.exists() or
                                               len(trajectory.read_text().splitlines()) < 50):
            time.sleep(0.2)
        killed = time.monotonic()
        server.kill()
        output, _ = runner.communicate(timeout=30)
        ended = time.monotonic() - killed
    finally:
        server.kill()
        server.communicate(timeout=10)
        runner.kill()
    assert runner.returncode == 1, output
    assert "LINK LOST" in output
    assert ended < 3.0 + 2.0  # link_timeout, and the time to write the folder
    lost = [e for e in events(tmp_path / "run") if e["event"] == "link_lost"]
    assert len(lost) == 1 and lost[0]["on_violation"]["abort_to"] == "home"
    metrics = json.loads((tmp_path / "run" / "metrics.json").read_text())
    assert metrics["link_lost"] and not metrics["completed"]
    assert events(tmp_path / "run")[-1]["event"] == "mission_finished"


def test_sigint_stops_the_run_cleanly_with_the_vehicle_holding(tmp_path):
    mission = ROOT / "missions" / "field_transit.yaml"
    port = free_udp_port()
    server = serve(mission, port, tmp_path / "truth")
    runner = run(mission, port, tmp_path / "run")
    try:
        trajectory = tmp_path / "run" / "trajectory.csv"
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and (not trajectory.exists() or
                                               len(trajectory.read_text().splitlines()) < 50):
            time.sleep(0.2)
        runner.send_signal(signal.SIGINT)
        output, _ = runner.communicate(timeout=30)
    finally:
        runner.kill()
        server.send_signal(signal.SIGTERM)
        server.communicate(timeout=20)
    assert runner.returncode == 130, output  # 128 + SIGINT, as `auv simulate` (mission.interrupt)
    assert "Traceback" not in output and "STOPPED" in output
    log = events(tmp_path / "run")
    assert any(e["event"] == "stopped" and e["reason"] == "stopped by SIGINT" for e in log)
    metrics = json.loads((tmp_path / "run" / "metrics.json").read_text())
    assert metrics["stopped"] and not metrics["completed"]
    assert [e["status"] for e in metrics["elements"]][-1] == "skipped"
