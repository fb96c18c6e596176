"""The Zenoh driver on loopback (peer to peer, no router): ROS 2 messages published by another session reach the
sink as the agents' types, a stereo pair only when all four parts of a stamp have come, and the driver's request
reaches the publisher's side."""

from __future__ import annotations

import json
import socket
import threading
import time
from typing import Any

import numpy as np
import pytest

from mission.language.models import Mbes, Scanner, Stereo
from mission.plugin_api import StereoImages
from mission.sensors import DriverContext, SensorFrame, open_driver
from mission.sensors import ros_msgs as ros
from mission.sensors.zenoh_keys import open_session
from mission.vehicle import ScanFrame, SonarPing

pytest.importorskip("zenoh")
pytest.importorskip("rosbags")


def free_tcp_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class Sink:
    def __init__(self) -> None:
        self.frames: list[SensorFrame] = []
        self.arrived = threading.Event()

    def __call__(self, frame: SensorFrame) -> None:
        self.frames.append(frame)
        self.arrived.set()


def wait_for(predicate: Any, timeout: float = 5.0) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(0.02)
    return False


@pytest.fixture
def publisher() -> Any:
    port = free_tcp_port()
    session = open_session(listen=[f"tcp/127.0.0.1:{port}"])
    yield session, f"auv/test?connect=tcp/127.0.0.1:{port}"
    session.close()


def test_a_multibeam_ping_crosses_loopback_as_a_point_cloud(publisher: Any) -> None:
    session, address = publisher
    sink = Sink()
    driver = open_driver(f"zenoh:{address}", DriverContext("mbes", Mbes(), sink))
    try:
        time.sleep(0.5)  # the peers connect
        angles = np.linspace(-60.0, 60.0, 256)
        ranges = np.linspace(20.0, 80.0, 256)
        hit = np.arange(256) % 7 != 0
        msg = ros.ray_cloud_msg(12.3, ros.mbes_directions(angles), ranges, hit, "mbes")
        session.put("auv/test/mbes/points", ros.encode(msg))
        assert sink.arrived.wait(5.0)
    finally:
        driver.close()
    got = sink.frames[0]
    assert isinstance(got, SonarPing)
    assert got.time == pytest.approx(12.3, abs=1e-9)
    assert np.allclose(got.angles_deg, angles, atol=1e-3)
    assert np.allclose(got.ranges, ranges, rtol=1e-6)
    assert np.array_equal(got.hit, hit)
    assert np.isnan(got.north)  # placed onboard, at its stamp


def test_a_scanner_frame_keeps_its_ray_directions_in_the_body_frame(publisher: Any) -> None:
    session, address = publisher
    sink = Sink()
    driver = open_driver(f"zenoh:{address}", DriverContext("scanner", Scanner(max_range=12.0), sink))
    try:
        time.sleep(0.5)
        rng = np.random.default_rng(1)
        dirs = rng.normal(size=(50, 3))
        dirs /= np.linalg.norm(dirs, axis=1)[:, None]
        ranges = rng.uniform(1.0, 12.0, 50)
        session.put("auv/test/scanner/points", ros.encode(ros.ray_cloud_msg(3.5, dirs, ranges, ranges < 11,
                                                                            "base_link")))
        assert sink.arrived.wait(5.0)
    finally:
        driver.close()
    got = sink.frames[0]
    assert isinstance(got, ScanFrame)
    assert np.allclose(got.directions_body, dirs, atol=1e-6)
    assert np.allclose(got.ranges, ranges, rtol=1e-6)
    assert got.max_range == 12.0


def test_a_stereo_pair_goes_out_only_when_both_images_and_both_camera_infos_have_come(publisher: Any) -> None:
    session, address = publisher
    sink = Sink()
    driver = open_driver(f"zenoh:{address}", DriverContext("stereo", Stereo(), sink))
    rng = np.random.default_rng(2)
    left = rng.integers(0, 255, (90, 120), dtype=np.uint8)
    right = rng.integers(0, 255, (90, 120), dtype=np.uint8)
    K = np.array([[100.0, 0, 60], [0, 100.0, 45], [0, 0, 1]])
    try:
        time.sleep(0.5)
        t = 7.25
        session.put("auv/test/stereo/left/image_raw", ros.encode(ros.image_msg(t, left, "stereo_left")))
        session.put("auv/test/stereo/left/camera_info",
                    ros.encode(ros.camera_info_msg(t, K, 120, 90, 0.25, "stereo_left", False)))
        session.put("auv/test/stereo/right/image_raw", ros.encode(ros.image_msg(t, right, "stereo_right")))
        time.sleep(0.3)
        assert sink.frames == []  # three parts of four
        session.put("auv/test/stereo/right/camera_info",
                    ros.encode(ros.camera_info_msg(t, K, 120, 90, 0.25, "stereo_right", True)))
        assert sink.arrived.wait(5.0)
    finally:
        driver.close()
    pair = sink.frames[0]
    assert isinstance(pair, StereoImages)
    assert pair.time == pytest.approx(7.25)
    assert np.array_equal(pair.left, left) and np.array_equal(pair.right, right)
    assert np.allclose(pair.K, K) and pair.baseline == pytest.approx(0.25)


def test_the_driver_tells_the_publisher_which_sensors_are_wanted(publisher: Any) -> None:
    session, address = publisher
    heard: list[dict[str, Any]] = []
    sub = session.declare_subscriber("auv/test/*/request",
                                     lambda s: heard.append(json.loads(s.payload.to_bytes())))
    driver = open_driver(f"zenoh:{address}", DriverContext("stereo", Stereo(), Sink()))
    try:
        time.sleep(0.5)
        driver.request(True, 2.0)
        assert wait_for(lambda: {"on": True, "rate_hz": 2.0} in heard)
        driver.request(False, None)
        assert wait_for(lambda: heard[-1] == {"on": False, "rate_hz": None})
    finally:
        driver.close()
        sub.undeclare()
