"""`auv sim serve --zenoh` publishes the simulated payload streams a driver asks for, rendered from the vehicle
and stamped with the vehicle's clock: multibeam pings at the sonar's rate, and stereo pairs with the mission's
camera at the frame rate the driver requests; nothing is published for a sensor nobody asks for."""

from __future__ import annotations

import socket
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

pytest.importorskip("mujoco")
pytest.importorskip("zenoh")
pytest.importorskip("rosbags")

from mission.language.loader import load_mission  # noqa: E402
from mission.plugin_api import StereoImages  # noqa: E402
from mission.sensors import DriverContext, SensorFrame, open_driver  # noqa: E402
from mission.sim.serve import ServedVehicle  # noqa: E402
from mission.vehicle import SonarPing  # noqa: E402

HEADER = """
world: WORLD
home: {north: 150, east: 195, depth: 50, heading: 0}
sensors:
  mbes: {beams: 64, swath_deg: 120, max_range: 80, rate_hz: 10}
  stereo: {width: 320, height: 240, fx: 300, baseline: 0.2, rate_hz: 10, max_range: 8}
  dvl: {drift_percent: 0.5}
"""


def free_port(kind: int) -> int:
    with socket.socket(socket.AF_INET, kind) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class Sink:
    def __init__(self) -> None:
        self.frames: list[SensorFrame] = []
        self.lock = threading.Lock()

    def __call__(self, frame: SensorFrame) -> None:
        with self.lock:
            self.frames.append(frame)


def test_serve_publishes_the_streams_drivers_ask_for_stamped_with_the_vehicle_clock(write_mission: Any,
                                                                                   tmp_path: Path) -> None:
    from tests.conftest import WORLD

    route = "  - id: hold\n    transit: {to: home, navigation: dead-reckoning}\n"
    mission = load_mission(write_mission("published", route, header=HEADER.replace("WORLD", str(WORLD))))
    tcp = free_port(socket.SOCK_STREAM)
    endpoint = f"auv/sim?connect=tcp/127.0.0.1:{tcp}"
    pings, pairs = Sink(), Sink()
    with ServedVehicle(mission, f"udpout:127.0.0.1:{free_port(socket.SOCK_DGRAM)}", speedup=5.0,
                       zenoh=[f"tcp/127.0.0.1:{tcp}"]) as served:
        assert mission.sensors.mbes is not None and mission.sensors.stereo is not None
        sonar = open_driver(f"zenoh:{endpoint}", DriverContext("mbes", mission.sensors.mbes, pings))
        camera = open_driver(f"zenoh:{endpoint}", DriverContext("stereo", mission.sensors.stereo, pairs))
        try:
            time.sleep(1.5)
            assert pings.frames == [] and pairs.frames == []  # nobody asked yet
            sonar.request(True, None)
            camera.request(True, 2.0)
            end = time.monotonic() + 20
            while time.monotonic() < end and (len(pairs.frames) < 3 or len(pings.frames) < 30):
                time.sleep(0.1)
        finally:
            sonar.close()
            camera.close()
    summary = served.summary
    assert summary is not None
    with pings.lock:
        got_pings = [p for p in pings.frames if isinstance(p, SonarPing)]
    stamps = np.array([p.time for p in got_pings])
    assert len(got_pings) >= 30 and len(got_pings[0].ranges) == 64
    # 10 Hz of the vehicle's clock: the simulator casts the pings due in a 0.2 s step at the step's end, stamped
    # with it (two per step)
    assert np.all(np.diff(stamps) >= 0) and (len(stamps) - 1) / (stamps[-1] - stamps[0]) == pytest.approx(10, rel=0.1)
    assert got_pings[0].hit.mean() > 0.9  # the seabed 10 m below
    good = got_pings[0].ranges[got_pings[0].hit]
    assert 8.0 < good.min() < 12.0
    frames = [f for f in pairs.frames if isinstance(f, StereoImages)]
    assert len(frames) >= 3
    assert np.allclose(np.diff([f.time for f in frames]), 0.6, atol=0.01)  # 2 Hz asked, on the 0.2 s step grid
    f = frames[0]
    assert f.left.shape == (240, 320) and f.K[0, 0] == pytest.approx(300.0) and f.baseline == pytest.approx(0.2)
    assert f.left.std() > 1.0  # a rendered seabed, not a blank image
    assert stamps[-1] <= summary.sim_time + 1e-6
    assert summary.published["scanner"] == 0
