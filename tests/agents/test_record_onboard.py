"""The `record` action in `auv run`: a vehicle that streams stereo (here the `replay` driver, beside the vehicle
that `auv sim serve` flies over MAVLink on loopback) has its element's pairs recorded in `stereo/ID/` with the
estimated left-camera pose of each, as `auv simulate` records them."""

from __future__ import annotations

import json
import signal
import socket
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from mission.plugin_api import StereoImages
from mission.sim.stereo_record import read_stereo_recording
from mission.stereo_recording import StereoRecorder

pytest.importorskip("mujoco")
pytest.importorskip("pymavlink")

ROOT = Path(__file__).resolve().parents[2]
AUV = [sys.executable, "-m", "mission"]

MISSION = """\
name: record-onboard
world: WORLD
seed: 3
home: {north: 0, east: 0, depth: 20, heading: 0}
sensors:
  stereo: {width: 64, height: 48, fx: 50, baseline: 0.25, rate_hz: 10, max_range: 8, driver: "replay:CLIP?loop=1"}
  usbl: {sigma: 1.5, rate_hz: 0.5}
  dvl: {drift_percent: 0.5}
safety:
  geofence: [[-60, -60], [-60, 460], [360, 460], [360, -60]]
  max_depth: 120
  max_duration: 10min
route:
  - id: go
    transit: {to: {north: 30, east: 0}, depth: 20}
    actions: [record]
  - id: back
    transit: {to: {north: 0, east: 0}, depth: 20}
"""


def free_port(kind: int) -> int:
    with socket.socket(socket.AF_INET, kind) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def write_clip(folder: Path, frames: int = 20) -> None:
    """A 2-second 10 Hz stereo clip of noise images, in the KITTI layout the replay driver plays."""
    rng = np.random.default_rng(5)
    K = np.array([[50.0, 0.0, 32.0], [0.0, 50.0, 24.0], [0.0, 0.0, 1.0]])
    with StereoRecorder(folder, ("poses",)) as recorder:
        for i in range(frames):
            left = rng.integers(0, 255, (48, 64), dtype=np.uint8)
            recorder.write(StereoImages(0.1 * i, left, np.roll(left, 3, axis=1), K, 0.25), np.eye(4))


def test_auv_run_records_the_streamed_pairs_of_the_element_with_record_only(tmp_path: Path) -> None:
    write_clip(tmp_path / "clip")
    mission = tmp_path / "mission.yaml"
    mission.write_text(MISSION.replace("WORLD", str(ROOT / "worlds" / "sps_field.yaml"))
                       .replace("CLIP", str(tmp_path / "clip")), encoding="utf-8")
    udp = free_port(socket.SOCK_DGRAM)
    out = tmp_path / "run"
    server = subprocess.Popen([*AUV, "sim", "serve", str(mission), "--mavlink", f"udpout:127.0.0.1:{udp}",
                               "--speedup", "5", "--out", str(tmp_path / "truth"), "-q"], cwd=ROOT,
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        runner = subprocess.run([*AUV, "run", str(mission), "--vehicle", f"mavlink:udpin:127.0.0.1:{udp}",
                                 "--out", str(out)], cwd=ROOT, capture_output=True, text=True, timeout=120)
    finally:
        server.send_signal(signal.SIGTERM)
        server.communicate(timeout=20)
    assert runner.returncode == 0, runner.stdout + runner.stderr
    metrics = json.loads((out / "metrics.json").read_text(encoding="utf-8"))
    go, back = metrics["elements"]
    assert go["status"] == back["status"] == "succeeded"
    assert go["actions"]["record"] == "stereo/go" and back["actions"] == {}
    assert not (out / "stereo" / "back").exists()
    recording = read_stereo_recording(out / "stereo" / "go")
    assert len(recording) == go["actions"]["recorded_pairs"] >= 10
    assert float(recording.K[0, 0]) == 50.0 and recording.baseline == 0.25
    # the estimated left camera: looking down (optical axis = world down), moving north with the vehicle
    assert np.allclose(recording.poses[:, :3, 2], [0.0, 0.0, 1.0], atol=0.05)
    north = recording.poses[:, 0, 3]
    assert north[-1] - north[0] > 10.0 and abs(float(np.median(recording.poses[:, 2, 3])) - 20.0) < 1.5
