"""`auv sim serve` seen from a plain pymavlink GCS over real UDP on loopback: the truth written as it goes,
ArduSub's GCS failsafe, setpoints ignored outside GUIDED, the GUIDED velocity timeout, and the CLI stopping
cleanly on SIGTERM."""

from __future__ import annotations

import csv
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("pymavlink")

from mission.language.loader import load_mission  # noqa: E402
from mission.language.models import Mission  # noqa: E402
from mission.sim.serve import ServedVehicle  # noqa: E402
from mission.vehicles.mavlink_link import mavutil  # noqa: E402

ROOT = Path(__file__).resolve().parents[3]
ROUTE = """  - id: leg
    transit: {to: {north: 40, east: 40}, depth: 10}
"""
GUIDED, POSHOLD = 4, 16


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@pytest.fixture
def mission(write_mission) -> Mission:
    return load_mission(write_mission("served", ROUTE))


class Gcs:
    """A ground station written with pymavlink alone (system 255, as ArduSub's failsafe expects)."""

    def __init__(self, port: int):
        self.conn = mavutil().mavlink_connection(f"udpin:127.0.0.1:{port}", source_system=255)

    def beat(self) -> None:
        self.conn.mav.heartbeat_send(6, 8, 0, 0, 4)  # MAV_TYPE_GCS, MAV_AUTOPILOT_INVALID

    def command(self, command: int, *params: float) -> int:
        p = list(params) + [0.0] * (7 - len(params))
        self.conn.mav.command_long_send(1, 1, command, 0, *p)
        ack = self.conn.recv_match(type="COMMAND_ACK", blocking=True, timeout=3)
        assert ack is not None and ack.command == command
        return int(ack.result)

    def arm_in(self, mode: int) -> None:
        assert self.conn.wait_heartbeat(timeout=5) is not None
        self.beat()
        assert self.command(176, 1, mode) == 0
        assert self.command(400, 1) == 0

    def newest(self, kind: str, wall: float = 0.3) -> Any:
        """The newest message of a type received within `wall` seconds."""
        got, end = None, time.monotonic() + wall
        while time.monotonic() < end:
            msg = self.conn.recv_match(type=kind, blocking=True, timeout=0.05)
            got = msg or got
        return got

    def close(self) -> None:
        self.conn.close()


def rows(path: Path) -> list[dict[str, str]]:
    with path.open(encoding="utf-8") as f:
        return list(csv.DictReader(f))


def test_serve_writes_the_truth_as_it_goes(mission: Mission, tmp_path: Path) -> None:
    port = free_udp_port()
    with ServedVehicle(mission, f"udpout:127.0.0.1:{port}", speedup=10, out=tmp_path / "truth"):
        time.sleep(1.5)
        during = rows(tmp_path / "truth" / "trajectory.csv")  # read while serving: flushed within FLUSH_PERIOD
    after = rows(tmp_path / "truth" / "trajectory.csv")
    assert (tmp_path / "truth" / "mission.yaml").is_file() and (tmp_path / "truth" / "world.yaml").is_file()
    assert float(during[-1]["time"]) > 3.0  # on disk while serving (1.5 s of wall time at 10x, less a flush)
    times = [float(r["time"]) for r in after]
    assert times == pytest.approx([0.2 * (k + 1) for k in range(len(times))], abs=1e-3)
    assert rows(tmp_path / "truth" / "usbl.csv")  # the acoustic fixes, every 2 s of vehicle time


def test_the_gcs_failsafe_disarms_the_vehicle_when_the_gcs_heartbeat_stops(mission: Mission) -> None:
    port = free_udp_port()
    with ServedVehicle(mission, f"udpout:127.0.0.1:{port}", speedup=10, gcs_timeout=1.0) as served:
        gcs = Gcs(port)
        try:
            gcs.arm_in(GUIDED)
            silent_from = time.monotonic()
            deadline = silent_from + 3.0
            while time.monotonic() < deadline and not any(e["event"] == "disarmed" for e in served.events):
                time.sleep(0.05)
            disarmed_after = time.monotonic() - silent_from
            beat = gcs.newest("HEARTBEAT", 1.5)
        finally:
            gcs.close()
    names = [e["event"] for e in served.events]
    assert names[-2:] == ["gcs_failsafe", "disarmed"]
    assert 1.0 <= disarmed_after < 2.0
    assert not beat.base_mode & 128 and beat.system_status == 5  # disarmed, MAV_STATE_CRITICAL


def test_a_set_mode_message_is_acknowledged_and_changes_the_mode(mission: Mission) -> None:
    port = free_udp_port()
    with ServedVehicle(mission, f"udpout:127.0.0.1:{port}", speedup=10) as served:
        gcs = Gcs(port)
        try:
            assert gcs.conn.wait_heartbeat(timeout=5) is not None
            gcs.conn.mav.set_mode_send(1, 1, 9)  # SURFACE
            ack = gcs.conn.recv_match(type="COMMAND_ACK", blocking=True, timeout=3)
            gcs.conn.mav.set_mode_send(1, 1, 77)  # no such ArduSub mode
            nak = gcs.conn.recv_match(type="COMMAND_ACK", blocking=True, timeout=3)
            beat = gcs.newest("HEARTBEAT", 1.2)
        finally:
            gcs.close()
    assert (ack.command, ack.result, nak.result) == (11, 0, 2)  # SET_MODE: accepted, then denied
    assert beat.custom_mode == 9
    assert [e["mode"] for e in served.events if e["event"] == "mode_changed"] == ["SURFACE"]


def test_setpoints_outside_guided_are_ignored_and_the_vehicle_holds(mission: Mission, tmp_path: Path) -> None:
    port = free_udp_port()
    with ServedVehicle(mission, f"udpout:127.0.0.1:{port}", speedup=20, out=tmp_path / "truth"):
        gcs = Gcs(port)
        try:
            gcs.arm_in(POSHOLD)
            for _ in range(20):  # run north at 1 m/s, 1 s of wall time = 20 s of vehicle time
                gcs.beat()
                gcs.conn.mav.set_position_target_local_ned_send(0, 1, 1, 1, 0b100111000111, 0, 0, 0, 1.0, 0, 0,
                                                                0, 0, 0, 0, 0)
                time.sleep(0.05)
        finally:
            gcs.close()
    last = rows(tmp_path / "truth" / "trajectory.csv")[-1]
    assert abs(float(last["north"])) < 1.5 and abs(float(last["east"])) < 1.5  # POSHOLD: held against the current


def test_a_guided_velocity_setpoint_times_out_after_3_s_of_vehicle_time(mission: Mission) -> None:
    port = free_udp_port()
    with ServedVehicle(mission, f"udpout:127.0.0.1:{port}", speedup=10):
        gcs = Gcs(port)
        try:
            gcs.arm_in(GUIDED)
            gcs.conn.mav.set_position_target_local_ned_send(0, 1, 1, 1, 0b110111000111, 0, 0, 0, 1.0, 0, 0,
                                                            0, 0, 0, 0, 0)  # a bare velocity: north at 1 m/s
            sent = gcs.newest("LOCAL_POSITION_NED", 0.01).time_boot_ms
            seen = []
            end = time.monotonic() + 1.2
            while time.monotonic() < end:
                msg = gcs.conn.recv_match(type="LOCAL_POSITION_NED", blocking=True, timeout=0.1)
                if msg is not None:
                    seen.append((msg.time_boot_ms - sent, msg.vx))
        finally:
            gcs.close()
    peak_ms, peak = max(seen, key=lambda s: s[1])
    assert peak > 0.5 and peak_ms < 3500  # accelerating at 0.2 m/s² until the setpoint times out
    assert seen[-1][0] > 7000 and abs(seen[-1][1]) < 0.05  # then stopped


def test_the_cli_serves_the_vehicle_and_stops_cleanly_on_sigterm(tmp_path: Path) -> None:
    port = free_udp_port()
    out = tmp_path / "truth"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.Popen([sys.executable, "-m", "mission", "sim", "serve", str(ROOT / "missions/field_transit.yaml"),
                             "--mavlink", f"udpout:127.0.0.1:{port}", "--speedup", "10", "--out", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    gcs = Gcs(port)
    try:
        beat = gcs.conn.wait_heartbeat(timeout=15)
        first = gcs.newest("LOCAL_POSITION_NED", 0.3)
        time.sleep(1.0)
        later = gcs.newest("LOCAL_POSITION_NED", 0.3)
    finally:
        gcs.close()
        proc.send_signal(signal.SIGTERM)
        stdout, stderr = proc.communicate(timeout=10)
    assert proc.returncode == 0, stderr
    assert beat.type == 12 and beat.autopilot == 3  # MAV_TYPE_SUBMARINE, MAV_AUTOPILOT_ARDUPILOTMEGA
    assert 5000 < later.time_boot_ms - first.time_boot_ms < 16000  # ~1.3 s of wall time at 10x
    assert "field-transit: serving" in stdout and "stopped:" in stdout
    assert float(rows(out / "trajectory.csv")[-1]["time"]) * 1000 >= later.time_boot_ms


def test_a_mission_exported_for_mavlink_uploads_to_serve_and_reads_back_item_for_item(tmp_path: Path) -> None:
    """`auv export --format mavlink --upload` against `auv sim serve`: every item is acknowledged and stored, and
    a download (MISSION_REQUEST_LIST) gives them back to the 1e-7° of MISSION_ITEM_INT."""
    from mission.export.mavlink_plan import read_wpl

    path = ROOT / "missions" / "field_survey.yaml"
    plan = tmp_path / "plan.waypoints"
    port = free_udp_port()
    with ServedVehicle(load_mission(path), f"udpout:127.0.0.1:{port}", speedup=5) as served:
        out = subprocess.run([sys.executable, "-m", "mission", "export", str(path), "--format", "mavlink", "--out",
                              str(plan), "--upload", f"udpin:127.0.0.1:{port}"], capture_output=True, text=True,
                             timeout=120)
        assert out.returncode == 0, out.stderr
        items = read_wpl(plan)
        [uploaded] = [e for e in served.events if e["event"] == "mission_uploaded"]
        assert uploaded["items"] == len(items) > 5
        gcs = Gcs(port)
        try:
            assert gcs.conn.wait_heartbeat(timeout=5) is not None  # a udpin link learns its peer from a packet
            gcs.conn.mav.mission_request_list_send(1, 1)
            count = gcs.conn.recv_match(type="MISSION_COUNT", blocking=True, timeout=5)
            assert count is not None and count.count == len(items)
            for it in items:
                gcs.conn.mav.mission_request_int_send(1, 1, it.seq)
                back = gcs.conn.recv_match(type="MISSION_ITEM_INT", blocking=True, timeout=5)
                assert back is not None and (back.seq, back.command, back.frame) == (it.seq, it.command, it.frame)
                assert back.x == round(it.lat * 1e7) and back.y == round(it.lon * 1e7)
                assert back.z == pytest.approx(it.z, abs=1e-3)
        finally:
            gcs.close()
