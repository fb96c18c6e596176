"""MAVLink and IMC plans of the plannable route: the MAVLink file reloads through pymavlink's `mavwp` within
0.15 m, the upload crosses a real MAVLink mission-protocol endpoint on loopback, the IMC plan serialises and
deserialises to the same path within 1 mm, and adaptive elements are refused by name."""

from __future__ import annotations

import socket
import threading
from pathlib import Path
from typing import Any

import export_cases
import numpy as np
import pytest

from mission.errors import MissionError
from mission.export import export
from mission.export.imc_plan import read_imc_plan
from mission.export.mavlink_plan import (
    MAV_CMD_NAV_WAYPOINT,
    MAV_FRAME_GLOBAL_RELATIVE_ALT,
    MAV_FRAME_GLOBAL_TERRAIN_ALT,
    read_wpl,
    upload_mission,
)
from mission.export.plan import plan_legs
from mission.geodesy import geodetic_to_ned
from mission.language import load_mission
from mission.vehicles.mavlink_link import mavutil as mavlink2

ORIGIN = (42.95, 131.85)


@pytest.fixture
def mission_file(tmp_path: Path) -> Path:
    return export_cases.far_mission(tmp_path)


@pytest.fixture
def adaptive_mission_file(tmp_path: Path) -> Path:
    return export_cases.adaptive_mission(tmp_path)


def _planned(mission_file: Path) -> tuple[np.ndarray, list[Any]]:
    legs = plan_legs(load_mission(mission_file, environment=False))
    return np.array([p for leg in legs for p in leg.points_ne]), legs


def test_the_mavlink_mission_reloads_through_mavwp_within_15_cm(mission_file: Path, tmp_path: Path) -> None:
    out = tmp_path / "far.waypoints"
    export(mission_file, "mavlink", out)
    mavutil = mavlink2()  # pymavlink speaking MAVLink 2 (the dialect is chosen once per process)
    from pymavlink import mavwp

    loader = mavwp.MAVWPLoader()
    n = loader.load(str(out))
    items = [loader.wp(i) for i in range(n)]
    waypoints = [w for w in items[1:] if w.command == MAV_CMD_NAV_WAYPOINT]
    planned, legs = _planned(mission_file)
    assert len(waypoints) == len(planned)
    north, east = geodetic_to_ned([w.x for w in waypoints], [w.y for w in waypoints], *ORIGIN)
    error = np.hypot(north - planned[:, 0], east - planned[:, 1])
    assert error.max() < 0.15
    # depth legs are relative altitude below the surface, the survey flies at an altitude above the seabed
    frames = {(w.frame, round(w.z, 3)) for w in waypoints}
    assert frames == {(MAV_FRAME_GLOBAL_RELATIVE_ALT, -40.0), (MAV_FRAME_GLOBAL_TERRAIN_ALT, 20.0),
                      (MAV_FRAME_GLOBAL_RELATIVE_ALT, 0.0)}
    speeds = [w.param2 for w in items if w.command == mavutil.mavlink.MAV_CMD_DO_CHANGE_SPEED]
    assert speeds == [1.5, 1.2, 1.5]
    assert waypoints[0].param2 == 4.0  # the transit's capture radius is the acceptance radius


def _free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _vehicle(port: int, received: list[Any], done: threading.Event) -> None:
    """A vehicle's side of the mission protocol, on a real pymavlink endpoint: ask for every item, then ACK."""
    mavutil = mavlink2()
    link = mavutil.mavlink_connection(f"udpin:127.0.0.1:{port}", source_system=1, source_component=1)
    try:
        count = link.recv_match(type="MISSION_COUNT", blocking=True, timeout=5)
        if count is None:
            return
        for seq in range(count.count):
            link.mav.mission_request_int_send(255, 190, seq)
            item = link.recv_match(type="MISSION_ITEM_INT", blocking=True, timeout=5)
            if item is None:
                return
            received.append(item)
        link.mav.mission_ack_send(255, 190, mavutil.mavlink.MAV_MISSION_ACCEPTED)
    finally:
        done.set()
        link.close()


def test_the_mission_uploads_over_the_mavlink_mission_protocol(mission_file: Path, tmp_path: Path) -> None:
    out = tmp_path / "far.waypoints"
    export(mission_file, "mavlink", out)
    items = read_wpl(out)
    port, received, done = _free_udp_port(), [], threading.Event()
    vehicle = threading.Thread(target=_vehicle, args=(port, received, done), daemon=True)
    vehicle.start()
    upload_mission(items, f"udpout:127.0.0.1:{port}", timeout=5.0)
    assert done.wait(5)
    assert [r.seq for r in received] == list(range(len(items)))
    got = np.array([[r.x, r.y] for r in received]) / 1e7
    sent = np.array([[it.lat, it.lon] for it in items])
    assert np.abs(got - sent).max() <= 0.6e-7  # MISSION_ITEM_INT: 1e-7 degree integers
    assert [r.command for r in received] == [it.command for it in items]


def test_the_imc_plan_serialises_and_deserialises_to_the_same_path_within_1_mm(mission_file: Path,
                                                                                tmp_path: Path) -> None:
    out = tmp_path / "far.imc"
    export(mission_file, "imc", out)
    plan_id, maneuvers = read_imc_plan(out.read_bytes(), *ORIGIN)
    planned, legs = _planned(mission_file)
    assert plan_id == "far-survey"
    assert [(m.maneuver_id, m.kind, m.z_units, m.z) for m in maneuvers] == [
        ("out", "Goto", "depth", 40.0), ("far-field", "FollowPath", "altitude", 20.0), ("back", "Goto", "depth", 0.0)]
    back = np.array([p for m in maneuvers for p in m.points_ne])
    assert back.shape == planned.shape
    assert np.abs(back - planned).max() < 0.001


@pytest.mark.parametrize("fmt", ["mavlink", "imc"])
def test_adaptive_elements_are_refused_by_name_where_they_stand(adaptive_mission_file: Path, tmp_path: Path,
                                                                fmt: str) -> None:
    with pytest.raises(MissionError) as caught:
        export(adaptive_mission_file, fmt, tmp_path / "x")
    (diag,) = caught.value.diagnostics
    assert "'look-closer' (explore)" in diag.message and "adaptive" in diag.message
    lines = adaptive_mission_file.read_text().splitlines()
    assert "look-closer" in lines[diag.line - 1]
    assert not (tmp_path / "x").exists()
