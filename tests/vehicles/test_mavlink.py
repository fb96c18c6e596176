"""The MAVLink adapter against `auv sim serve` over real UDP on loopback (pymavlink on both sides): connecting,
arming and GUIDED; commands moving the simulated vehicle as its truth file shows; the vehicle's clock; a pilot
taking over and handing back; link loss; bad addresses; and a vehicle without a rangefinder."""

from __future__ import annotations

import csv
import math
import socket
import threading
import time
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("pymavlink")

from mission.errors import LinkLostError, VehicleError  # noqa: E402
from mission.language.loader import load_mission  # noqa: E402
from mission.language.models import Mission  # noqa: E402
from mission.sim.serve import ServedVehicle  # noqa: E402
from mission.vehicle import Command  # noqa: E402
from mission.vehicles import VehicleOptions  # noqa: E402
from mission.vehicles import open_vehicle as open_by_uri  # noqa: E402
from mission.vehicles.mavlink import MavlinkVehicle, open_vehicle  # noqa: E402
from mission.vehicles.mavlink_link import mavutil  # noqa: E402

ROUTE = """  - id: leg
    transit: {to: {north: 40, east: 40}, depth: 10}
"""
ALTITUDE_ROUTE = """  - id: dive
    transit: {to: {north: 0, east: 0}, depth: 10}
  - id: low
    transit: {to: {north: 60, east: 60}, altitude: 8}
"""


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def free_tcp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


WORLD = Path(__file__).resolve().parents[2] / "worlds" / "sps_field.yaml"
HEADER = f"""
world: {WORLD}
sensors:
  usbl: {{sigma: 1.5, rate_hz: 0.5}}
  dvl: {{drift_percent: 0.5}}
safety:
  geofence: [[-60, -60], [-60, 460], [360, 460], [360, -60]]
  link_timeout: 2.0
"""


@pytest.fixture
def mission(write_mission) -> Mission:
    return load_mission(write_mission("mav", ROUTE, header=HEADER))


class Events:
    def __init__(self) -> None:
        self.seen: list[tuple[str, float, dict[str, Any]]] = []

    def __call__(self, event: str, time: float, **fields: Any) -> None:
        self.seen.append((event, time, fields))

    def named(self, event: str) -> list[dict[str, Any]]:
        return [f for e, _, f in self.seen if e == event]


def drive(vehicle: MavlinkVehicle, command: Command, seconds: float) -> None:
    """Apply `command` every tick for `seconds` of vehicle time."""
    nav = vehicle.observe().nav
    end = nav.time + seconds
    while nav.time < end - 1e-6:
        vehicle.apply(command)
        vehicle.advance()
        nav = vehicle.observe().nav


def truth_rows(out: Path) -> list[dict[str, str]]:
    with (out / "trajectory.csv").open(encoding="utf-8") as f:
        return list(csv.DictReader(f))


def test_the_adapter_connects_sets_guided_and_arms(mission: Mission) -> None:
    port = free_udp_port()
    with ServedVehicle(mission, f"udpout:127.0.0.1:{port}", speedup=20) as served:
        t0 = time.monotonic()
        vehicle = open_vehicle(f"udpin:127.0.0.1:{port}", mission, VehicleOptions(connect_timeout=5))
        try:
            opened = time.monotonic() - t0
            obs = vehicle.observe()
        finally:
            vehicle.close()
    assert opened < 3.0
    assert obs.in_control
    assert [e["event"] for e in served.events][:2] == ["mode_changed", "armed"]
    assert served.events[0]["mode"] == "GUIDED"
    assert obs.nav.altitude is not None and obs.nav.altitude > 10.0  # the field's seabed under the launch point


def test_the_entry_point_opens_the_adapter_by_uri_scheme(mission: Mission) -> None:
    port = free_udp_port()
    with ServedVehicle(mission, f"udpout:127.0.0.1:{port}", speedup=20):
        vehicle = open_by_uri(f"mavlink:udpin:127.0.0.1:{port}", mission, VehicleOptions(connect_timeout=5))
        vehicle.close()
    assert isinstance(vehicle, MavlinkVehicle)


def test_a_heading_speed_depth_command_moves_the_simulated_vehicle_as_the_truth_shows(
        mission: Mission, tmp_path: Path) -> None:
    port = free_udp_port()
    with ServedVehicle(mission, f"udpout:127.0.0.1:{port}", speedup=25, out=tmp_path / "truth"):
        vehicle = open_vehicle(f"udpin:127.0.0.1:{port}", mission, VehicleOptions(connect_timeout=5))
        try:
            start = vehicle.observe().nav
            drive(vehicle, Command(heading=90.0, speed=1.0, depth=10.0), 40.0)
            end = vehicle.observe().nav
        finally:
            vehicle.close()
    last = truth_rows(tmp_path / "truth")[-1]
    assert abs(float(last["depth"]) - 10.0) < 0.5
    assert abs(((float(last["heading"]) - 90.0 + 180.0) % 360.0) - 180.0) < 3.0
    assert float(last["east"]) > 20.0  # 40 s at up to 1 m/s, after turning from north
    assert end.time - start.time == pytest.approx(40.0, abs=0.25)
    assert abs(float(last["east"]) - end.east) < 3.0  # the estimate the adapter saw tracks the truth
    assert end.position_sigma == pytest.approx(float(last["position_sigma"]), abs=0.05)  # LOCAL_POSITION_NED_COV
    used_wh = mission.vehicle.energy_wh - end.energy_wh  # BATTERY_STATUS.energy_consumed, sent once a second
    assert 0.0 < used_wh and used_wh == pytest.approx(float(last["energy_wh"]), abs=0.15)


def test_a_station_command_holds_the_point(mission: Mission, tmp_path: Path) -> None:
    port = free_udp_port()
    station = (6.0, -4.0)
    with ServedVehicle(mission, f"udpout:127.0.0.1:{port}", speedup=25, out=tmp_path / "truth"):
        vehicle = open_vehicle(f"udpin:127.0.0.1:{port}", mission, VehicleOptions(connect_timeout=5))
        try:
            drive(vehicle, Command(heading=45.0, speed=0.0, depth=5.0, station=station), 60.0)
            nav = vehicle.observe().nav
        finally:
            vehicle.close()
    assert math.hypot(nav.north - station[0], nav.east - station[1]) < 0.3
    last = truth_rows(tmp_path / "truth")[-1]
    assert math.hypot(float(last["north"]) - station[0], float(last["east"]) - station[1]) < 3.0
    assert abs(float(last["depth"]) - 5.0) < 0.3


def test_an_altitude_command_follows_the_seabed_through_depth_setpoints(write_mission, tmp_path: Path) -> None:
    mission = load_mission(write_mission("low", ALTITUDE_ROUTE, header=HEADER))
    port = free_udp_port()
    with ServedVehicle(mission, f"udpout:127.0.0.1:{port}", speedup=50, out=tmp_path / "truth"):
        vehicle = open_vehicle(f"udpin:127.0.0.1:{port}", mission, VehicleOptions(connect_timeout=5))
        try:
            drive(vehicle, Command(heading=45.0, speed=0.5, altitude=8.0), 160.0)
        finally:
            vehicle.close()
    last = truth_rows(tmp_path / "truth")[-1]
    assert abs(float(last["altitude"]) - 8.0) < 1.0


def test_time_follows_the_vehicle_clock_at_speedup_10(mission: Mission) -> None:
    port = free_udp_port()
    with ServedVehicle(mission, f"udpout:127.0.0.1:{port}", speedup=10):
        vehicle = open_vehicle(f"udpin:127.0.0.1:{port}", mission, VehicleOptions(connect_timeout=5))
        try:
            t0, wall0 = vehicle.observe().nav.time, time.monotonic()
            for _ in range(50):
                vehicle.apply(Command(heading=0.0, speed=0.5, depth=2.0))
                vehicle.advance()
            t1, wall = vehicle.observe().nav.time, time.monotonic() - wall0
        finally:
            vehicle.close()
    assert t1 - t0 == pytest.approx(10.0, abs=0.25)
    assert 0.7 < wall < 2.5  # paced by the vehicle (not free-running); slack for a loaded machine


def test_a_mode_change_by_a_second_gcs_pauses_the_mission_and_guided_hands_it_back(mission: Mission) -> None:
    ours, pilots = free_udp_port(), free_udp_port()
    events = Events()
    mu = mavutil()
    with ServedVehicle(mission, [f"udpout:127.0.0.1:{ours}", f"udpout:127.0.0.1:{pilots}"], speedup=10):
        pilot = mu.mavlink_connection(f"udpin:127.0.0.1:{pilots}", source_system=254)
        vehicle = open_vehicle(f"udpin:127.0.0.1:{ours}", mission, VehicleOptions(connect_timeout=5, emit=events))
        try:
            assert pilot.wait_heartbeat(timeout=5) is not None
            drive(vehicle, Command(heading=0.0, speed=1.0, depth=5.0), 2.0)
            pilot.mav.command_long_send(1, 1, 176, 0, 1, 16, 0, 0, 0, 0, 0)  # DO_SET_MODE POSHOLD
            paused = _until(vehicle, lambda obs: not obs.in_control)
            at_pause = vehicle.observe().nav
            drive(vehicle, Command(heading=0.0, speed=1.0, depth=5.0), 3.0)
            held = vehicle.observe().nav
            pilot.mav.command_long_send(1, 1, 176, 0, 1, 4, 0, 0, 0, 0, 0)  # DO_SET_MODE GUIDED
            back = _until(vehicle, lambda obs: obs.in_control)
        finally:
            vehicle.close()
            pilot.close()
    assert paused and back
    assert held.north - at_pause.north < 1.0  # POSHOLD held it; our 1 m/s northwards was not sent for 3 s
    modes = [f["mode"] for f in events.named("vehicle_mode_changed")]
    assert modes == ["POSHOLD", "GUIDED"]


def _until(vehicle: MavlinkVehicle, condition: Any, wall: float = 3.0) -> bool:
    deadline = time.monotonic() + wall
    while time.monotonic() < deadline:
        vehicle.advance()
        if condition(vehicle.observe()):
            return True
    return False


def test_killing_the_server_gives_link_lost_within_the_link_timeout(mission: Mission) -> None:
    port = free_udp_port()
    served = ServedVehicle(mission, f"udpout:127.0.0.1:{port}", speedup=10).start()
    vehicle = open_vehicle(f"udpin:127.0.0.1:{port}", mission, VehicleOptions(connect_timeout=5))
    try:
        drive(vehicle, Command(heading=0.0, speed=0.5, depth=2.0), 1.0)
        served.stop()
        killed = time.monotonic()
        with pytest.raises(LinkLostError, match="no heartbeat"):
            while time.monotonic() - killed < 5.0:
                vehicle.apply(Command(heading=0.0, speed=0.5, depth=2.0))
                vehicle.advance()
                vehicle.observe()
        lost_after = time.monotonic() - killed
    finally:
        vehicle.close()
    assert lost_after <= mission.safety.link_timeout + 0.5


def test_no_heartbeat_is_a_vehicle_error_within_the_connect_timeout(mission: Mission) -> None:
    t0 = time.monotonic()
    with pytest.raises(VehicleError, match=r"no heartbeat from udpin:127.0.0.1:\d+ within 0.8 s"):
        open_vehicle(f"udpin:127.0.0.1:{free_udp_port()}", mission, VehicleOptions(connect_timeout=0.8))
    assert time.monotonic() - t0 < 1.5


@pytest.mark.parametrize("address", ["tcp:127.0.0.1:{tcp}", "/dev/no-such-serial-port,57600", "udpin:300.1.2.3:9"])
def test_an_unreachable_or_bad_address_is_a_one_line_vehicle_error(mission: Mission, address: str) -> None:
    address = address.format(tcp=free_tcp_port())
    t0 = time.monotonic()
    with pytest.raises(VehicleError) as err:
        open_vehicle(address, mission, VehicleOptions(connect_timeout=1.0))
    assert time.monotonic() - t0 < 2.0
    assert "\n" not in str(err.value) and address in str(err.value)


class BareVehicle:
    """A minimal MAVLink vehicle written with pymavlink alone: heartbeats and LOCAL_POSITION_NED, no
    rangefinder, and the COMMAND_ACK results it is told to give."""

    def __init__(self, address: str, results: dict[int, int]):
        self.conn = mavutil().mavlink_connection(address, source_system=1, source_component=1)
        self.results = results
        self.mode = 19  # MANUAL
        self.armed = False
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        t = 0
        while not self.stop.is_set():
            self.conn.mav.heartbeat_send(12, 3, 1 | (128 if self.armed else 0), self.mode, 3)
            self.conn.mav.local_position_ned_send(t, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0)
            t += 100
            end = time.monotonic() + 0.1
            while time.monotonic() < end:
                msg = self.conn.recv_match(type="COMMAND_LONG", blocking=True, timeout=0.02)
                if msg is not None:
                    result = self.results.get(msg.command, 0)
                    if msg.command == 176 and result == 0:
                        self.mode = int(msg.param2)
                    if msg.command == 400 and result == 0:
                        self.armed = msg.param1 == 1.0
                    self.conn.mav.command_ack_send(msg.command, result)

    def close(self) -> None:
        self.stop.set()
        self.thread.join(2.0)
        self.conn.close()


def test_a_mission_holding_an_altitude_is_refused_at_open_when_the_vehicle_has_no_rangefinder(write_mission) -> None:
    path = write_mission("low", ALTITUDE_ROUTE, header=HEADER)
    mission = load_mission(path)
    port = free_udp_port()
    bare = BareVehicle(f"udpout:127.0.0.1:{port}", {})
    try:
        with pytest.raises(VehicleError) as err:
            open_vehicle(f"udpin:127.0.0.1:{port}", mission, VehicleOptions(connect_timeout=1.5))
    finally:
        bare.close()
    line = next(n for n, text in enumerate(path.read_text().splitlines(), 1) if "altitude: 8" in text)
    assert str(err.value).startswith(f"{path}:{line}:")
    assert "transit 'low'" in str(err.value) and "rangefinder" in str(err.value)


def test_a_refused_arming_is_a_vehicle_error_naming_it(mission: Mission) -> None:
    port = free_udp_port()
    bare = BareVehicle(f"udpout:127.0.0.1:{port}", {400: 4})  # MAV_RESULT_FAILED
    try:
        with pytest.raises(VehicleError, match=r"refused arming \(MAV_RESULT_FAILED\)"):
            open_vehicle(f"udpin:127.0.0.1:{port}", mission, VehicleOptions(connect_timeout=1.5))
    finally:
        bare.close()


def test_aiding_off_selects_the_dead_reckoning_source_set_and_payloads_are_only_logged(mission: Mission) -> None:
    port = free_udp_port()
    events = Events()
    with ServedVehicle(mission, f"udpout:127.0.0.1:{port}", speedup=10) as served:
        vehicle = open_vehicle(f"udpin:127.0.0.1:{port}", mission, VehicleOptions(connect_timeout=5, emit=events))
        try:
            vehicle.set_aiding(False)
            vehicle.set_payload(frozenset({"mbes"}))
            vehicle.set_frame_rate(2.0)
            drive(vehicle, Command(heading=0.0, speed=0.5, depth=2.0), 2.0)
        finally:
            vehicle.close()
    assert [e["source_set"] for e in served.events if e["event"] == "ekf_source_set"] == [2]
    assert events.named("vehicle_command_refused") == []
    assert len(events.named("payload_not_streamed")) == 1  # logged once; nothing is sent for payloads


def test_a_refused_ekf_source_set_is_logged_and_the_mission_goes_on(mission: Mission) -> None:
    port = free_udp_port()
    events = Events()
    bare = BareVehicle(f"udpout:127.0.0.1:{port}", {42007: 2})  # MAV_RESULT_DENIED
    try:
        vehicle = open_vehicle(f"udpin:127.0.0.1:{port}", mission, VehicleOptions(connect_timeout=2, emit=events))
        try:
            vehicle.set_aiding(True)
            deadline = time.monotonic() + 2.0
            while time.monotonic() < deadline and not events.named("vehicle_command_refused"):
                vehicle.advance()
                obs = vehicle.observe()
        finally:
            vehicle.close()
    finally:
        bare.close()
    assert events.named("vehicle_command_refused") == [{"command": "SET_EKF_SOURCE_SET 1", "result": 2}]
    assert obs.in_control
