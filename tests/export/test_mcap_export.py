"""The MCAP log of a run folder reads back with the `mcap` reader: as many odometry messages as trajectory rows,
poses in ENU, the survey map as a point cloud, events on /rosout and the stereo pairs as images."""

from __future__ import annotations

import csv
import json
from collections import Counter
from pathlib import Path
from typing import Any

import cv2
import export_cases
import numpy as np
import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from mission.mcap_log import write_mcap

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def run_folder(tmp_path: Path) -> Path:
    return export_cases.synthetic_run(tmp_path)


def _messages(path: Path) -> list[tuple[str, object, int]]:
    with path.open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        return [(ch.topic, msg, m.log_time) for _, ch, m, msg in reader.iter_decoded_messages(log_time_order=True)]


def _rows(run: Path) -> int:
    with (run / "trajectory.csv").open(newline="") as f:
        return sum(1 for _ in csv.reader(f)) - 1


def test_the_mcap_log_has_an_odometry_message_per_trajectory_row_in_enu(run_folder: Path) -> None:
    count = write_mcap(run_folder)
    messages = _messages(run_folder / "run.mcap")
    assert count == len(messages)
    topics = Counter(topic for topic, _, _ in messages)
    assert topics["/odometry/estimated"] == topics["/odometry/true"] == _rows(run_folder) == 120
    assert topics["/fix/estimated"] == 120 and topics["/planned_path"] == 1
    assert topics["/map/seabed"] == topics["/map/occupied"] == 1 and topics["/rosout"] == 4
    first_true = next(msg for topic, msg, _ in messages if topic == "/odometry/true")
    p, q = first_true.pose.pose.position, first_true.pose.pose.orientation  # type: ignore[attr-defined]
    assert (p.x, p.y, p.z) == (9000.0, 9000.0, -40.0)  # x east, y north, z up
    assert np.isclose(2 * np.arctan2(q.z, q.w), np.radians(90.0 - 63.4))  # yaw from east, counter-clockwise
    cloud = next(msg for topic, msg, _ in messages if topic == "/map/seabed")
    assert cloud.width == 19 and cloud.point_step == 16  # type: ignore[attr-defined]  # 20 cells, one unknown
    levels = [msg.level for topic, msg, _ in messages if topic == "/rosout"]  # type: ignore[attr-defined]
    assert levels == [20, 20, 40, 30]


def test_a_recorded_stereo_stream_goes_in_as_mono8_images(run_folder: Path) -> None:
    stereo = run_folder / "stereo"
    for side in ("image_0", "image_1"):
        (stereo / side).mkdir(parents=True)
        for k in range(3):
            cv2.imwrite(str(stereo / side / f"{k:06d}.png"), np.full((8, 12), 40 * k + (side == "image_1"), np.uint8))
    (stereo / "times.txt").write_text("1.0\n1.5\n2.0\n")
    write_mcap(run_folder, run_folder / "with_stereo.mcap")
    images = [(t, msg) for topic, msg, t in _messages(run_folder / "with_stereo.mcap") if topic == "/stereo/right"]
    assert [t for t, _ in images] == [1_000_000_000, 1_500_000_000, 2_000_000_000]
    last = images[-1][1]
    assert (last.width, last.height, last.encoding) == (12, 8, "mono8")  # type: ignore[attr-defined]
    assert set(last.data) == {81}  # type: ignore[attr-defined]


def _layout_topics(layout: dict[str, Any]) -> set[str]:
    found: set[str] = set()
    for panel_id, config in layout["configById"].items():
        kind = panel_id.split("!")[0]
        if kind == "3D":
            found |= set(config["topics"])
        elif kind == "Image":
            found.add(config["imageMode"]["imageTopic"])
        elif kind == "map":
            found |= set(config["topicColors"])
        elif kind == "Plot":
            found |= {p["value"].split(".")[0] for p in config["paths"]}
        elif kind == "RosOut":
            found.add(config["topicToRender"])
    return found


def test_every_topic_the_foxglove_layout_shows_is_in_the_log(run_folder: Path, tmp_path: Path) -> None:
    layout = json.loads((ROOT / "docs" / "foxglove_layout.json").read_text())
    for side in ("image_0", "image_1"):
        (run_folder / "stereo" / side).mkdir(parents=True)
        cv2.imwrite(str(run_folder / "stereo" / side / "000000.png"), np.zeros((4, 4), np.uint8))
    (run_folder / "stereo" / "times.txt").write_text("1.0\n")
    write_mcap(run_folder, tmp_path / "all.mcap")
    written = {topic for topic, _, _ in _messages(tmp_path / "all.mcap")}
    shown = _layout_topics(layout)
    assert len(shown) >= 8 and shown <= written


def test_a_run_without_the_truth_logs_only_the_estimate(run_folder: Path) -> None:
    """`auv run` folders leave the true columns empty until `auv score` fills them."""
    path = run_folder / "trajectory.csv"
    with path.open(newline="") as f:
        rows = list(csv.reader(f))
    for row in rows[1:]:
        row[1:6] = [""] * 5
    with path.open("w", newline="") as f:
        csv.writer(f).writerows(rows)
    write_mcap(run_folder)
    topics = Counter(topic for topic, _, _ in _messages(run_folder / "run.mcap"))
    assert topics["/odometry/estimated"] == 120 and "/odometry/true" not in topics
