"""`auv run` gets its multibeam over Zenoh from `auv sim serve --zenoh` (two processes, MAVLink and Zenoh on
loopback) and maps a survey as `auv simulate` does; a stream killed mid-survey is a `sensor_lost` within the
sensor's timeout and the survey fails per its `on_failure` while the mission goes on."""

from __future__ import annotations

import json
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("mujoco")
pytest.importorskip("zenoh")
pytest.importorskip("rosbags")

ROOT = Path(__file__).resolve().parents[2]
AUV = [sys.executable, "-m", "mission"]
SPEEDUP = 5

# field_survey's survey cut down to the manifold's corner of the field, started at survey depth beside it.
SHORT_SURVEY = """\
name: short-stream-survey
origin: {lat: 42.95, lon: 131.85}
world: WORLD
seed: 7
home: {north: 112, east: 165, depth: 38, heading: 0}
vehicle: {cruise_speed: 1.5, max_speed: 2.0, max_yaw_rate: 15, max_vertical_speed: 0.5, turn_radius: 6,
          energy_wh: 4000, hotel_power_w: 60, propulsion_power_w: 180}
sensors:
  mbes: {beams: 256, swath_deg: 120, max_range: 80, rate_hz: 10, range_sigma: 0.05, timeout: 1.0}
  usbl: {sigma: 1.5, rate_hz: 0.5}
  dvl:  {drift_percent: 0.5}
safety:
  geofence: [[-60, -60], [-60, 460], [360, 460], [360, -60]]
  max_depth: 120
  min_altitude: 1.5
  max_duration: 1h
  on_violation: {abort_to: home}
objects:
  - id: manifold-1
    pose: {north: 150, east: 200, depth: 58, heading: 30}
    size: [8, 5, 2.5]
route:
  - id: survey
    survey:
      area: [[120, 170], [120, 230], [180, 230], [180, 170]]
      sensor: mbes
      altitude: 20
      overlap: 20%
      pattern: meander
      heading: auto
    actions: [map, detect_objects]
LAST"""
LAST_LEG = """\
  - id: leave
    transit: {to: {north: 112, east: 150}, depth: 38}
"""


def free_port(kind: int) -> int:
    with socket.socket(socket.AF_INET, kind) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def write_mission(tmp_path: Path, last: str = "") -> Path:
    mission = tmp_path / "short_survey.yaml"
    mission.write_text(SHORT_SURVEY.replace("WORLD", str(ROOT / "worlds" / "sps_field.yaml")).replace("LAST", last))
    return mission


def fly(mission: Path, tmp_path: Path, publish: bool, timeout: float = 120.0) -> tuple[int, str, Path]:
    udp, tcp = free_port(socket.SOCK_DGRAM), free_port(socket.SOCK_STREAM)
    out = tmp_path / "run"
    zenoh = ["--zenoh", f"tcp/127.0.0.1:{tcp}"] if publish else []
    server = subprocess.Popen([*AUV, "sim", "serve", str(mission), "--mavlink", f"udpout:127.0.0.1:{udp}",
                               "--speedup", str(SPEEDUP), "--out", str(tmp_path / "truth"), "-q", *zenoh], cwd=ROOT,
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        runner = subprocess.run([*AUV, "run", str(mission), "--vehicle", f"mavlink:udpin:127.0.0.1:{udp}",
                                 "--sensor-driver", f"zenoh:auv/sim?connect=tcp/127.0.0.1:{tcp}", "--out", str(out)],
                                cwd=ROOT, capture_output=True, text=True, timeout=timeout)
    finally:
        server.send_signal(signal.SIGTERM)
        server.communicate(timeout=20)
    return runner.returncode, runner.stdout + runner.stderr, out


def last_time(trajectory: Path) -> float:
    rows = trajectory.read_text().splitlines() if trajectory.exists() else []
    return float(rows[-1].split(",")[0]) if len(rows) > 1 else -1.0


def events(folder: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in (folder / "events.jsonl").read_text().splitlines()]


def test_a_survey_flown_on_zenoh_streams_maps_and_detects_as_the_simulation_does(tmp_path: Path) -> None:
    from mission import load_mission, simulate

    mission = write_mission(tmp_path)
    code, output, out = fly(mission, tmp_path, publish=True)
    assert code == 0, output
    flown = json.loads((out / "metrics.json").read_text())
    offline = simulate(load_mission(mission), out=tmp_path / "sim", plots=False).metrics
    survey, reference = flown["elements"][0], offline["elements"][0]
    assert survey["status"] == "succeeded"
    assert abs(survey["coverage_percent"] - reference["coverage_percent"]) <= 1.0, (survey, reference)
    assert len(survey["detections"]) == len(reference["detections"]) >= 1
    for got, want in zip(sorted(survey["detections"], key=lambda d: d["north"]),
                         sorted(reference["detections"], key=lambda d: d["north"]), strict=True):
        assert abs(got["north"] - want["north"]) <= 0.5 and abs(got["east"] - want["east"]) <= 0.5, (got, want)
    mbes = flown["sensors"]["mbes"]
    assert mbes["delivered"] >= 0.9 * survey["pings"] and mbes["lost_events"] == 0
    assert not any(e["event"] == "sensor_lost" for e in events(out))


def test_killing_the_stream_mid_survey_is_sensor_lost_within_the_timeout_and_the_mission_goes_on(
        tmp_path: Path) -> None:
    mission = write_mission(tmp_path, LAST_LEG)
    udp, tcp = free_port(socket.SOCK_DGRAM), free_port(socket.SOCK_STREAM)
    out = tmp_path / "run"
    server = subprocess.Popen([*AUV, "sim", "serve", str(mission), "--mavlink", f"udpout:127.0.0.1:{udp}",
                               "--speedup", str(SPEEDUP), "--zenoh", f"tcp/127.0.0.1:{tcp}", "-q"], cwd=ROOT,
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    runner = subprocess.Popen([*AUV, "run", str(mission), "--vehicle", f"mavlink:udpin:127.0.0.1:{udp}",
                               "--sensor-driver", f"zenoh:auv/sim?connect=tcp/127.0.0.1:{tcp}", "--out", str(out)],
                              cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        deadline = time.monotonic() + 60
        started = None
        while time.monotonic() < deadline:
            log = events(out) if (out / "events.jsonl").exists() else []
            started = next((e for e in log if e["event"] == "element_started" and e["element"] == "survey"), None)
            if started is not None and last_time(out / "trajectory.csv") > started["time"] + 20.0:
                break
            time.sleep(0.1)
        assert started is not None
        server.send_signal(signal.SIGUSR1)  # the payload streams stop; the vehicle goes on
        killed_at = last_time(out / "trajectory.csv")
        output, _ = runner.communicate(timeout=90)
    finally:
        runner.kill()
        server.send_signal(signal.SIGTERM)
        server.communicate(timeout=20)
    assert runner.returncode == 1, output
    log = events(out)
    lost = [e for e in log if e["event"] == "sensor_lost"]
    assert len(lost) == 1 and lost[0]["sensor"] == "mbes"
    assert 0.0 < lost[0]["time"] - killed_at <= (1.0 + 0.5) * SPEEDUP  # the 1 s timeout, in vehicle seconds
    metrics = json.loads((out / "metrics.json").read_text())
    statuses = {e["id"]: (e["status"], e.get("reason", "")) for e in metrics["elements"]}
    assert statuses["survey"] == ("failed", "sensor lost: mbes")
    assert statuses["leave"][0] == "succeeded"
    assert metrics["sensors"]["mbes"]["delivered"] >= 150  # the survey had its pings until the kill
