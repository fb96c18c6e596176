"""`auv export` in a real process: files written, and bad input as one line on stderr with exit code 1."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import export_cases
import pytest

CLI = "from mission.cli import main\nraise SystemExit(main(sys.argv[1:]))"


@pytest.fixture
def mission_file(tmp_path: Path) -> Path:
    return export_cases.far_mission(tmp_path)


@pytest.fixture
def run_folder(tmp_path: Path) -> Path:
    return export_cases.synthetic_run(tmp_path)


@pytest.fixture
def adaptive_mission_file(tmp_path: Path) -> Path:
    return export_cases.adaptive_mission(tmp_path)


@pytest.fixture
def no_origin_mission_file(tmp_path: Path) -> Path:
    return export_cases.no_origin_mission(tmp_path)


def _auv(*args: str | Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-c", "import sys\n" + CLI, "export", *map(str, args)],
                          capture_output=True, text=True, timeout=120)


@pytest.mark.parametrize("fmt", ["geojson", "kml", "mavlink", "imc"])
def test_export_writes_the_file_and_says_what_it_holds(mission_file: Path, tmp_path: Path, fmt: str,
                                                       capsys: pytest.CaptureFixture[str]) -> None:
    from mission.cli import main

    out = tmp_path / f"plan.{fmt}"
    assert main(["export", str(mission_file), "--format", fmt, "--out", str(out)]) == 0
    assert out.stat().st_size > 0 and str(out) in capsys.readouterr().out


def test_an_export_without_an_origin_is_one_located_line(no_origin_mission_file: Path, tmp_path: Path) -> None:
    done = _auv(no_origin_mission_file, "--format", "geojson", "--out", tmp_path / "x.geojson")
    assert done.returncode == 1
    assert done.stderr.count("\n") == 1 and "Traceback" not in done.stderr
    assert done.stderr.startswith(f"{no_origin_mission_file}:1:1: ") and "origin" in done.stderr


def test_an_adaptive_element_to_mavlink_is_one_line_naming_it(adaptive_mission_file: Path, tmp_path: Path) -> None:
    done = _auv(adaptive_mission_file, "--format", "mavlink", "--out", tmp_path / "x.waypoints")
    assert done.returncode == 1
    assert done.stderr.count("\n") == 1 and "'look-closer' (explore)" in done.stderr


def test_a_folder_that_is_not_a_run_folder_is_one_line(tmp_path: Path) -> None:
    done = _auv(tmp_path, "--format", "mcap")
    assert done.returncode == 1
    assert done.stderr.count("\n") == 1 and "not a complete run folder" in done.stderr


def test_a_run_folder_exports_to_mcap_inside_it(run_folder: Path) -> None:
    done = _auv(run_folder, "--format", "mcap")
    assert done.returncode == 0, done.stderr
    assert (run_folder / "run.mcap").is_file() and "messages" in done.stdout


def test_simulate_with_mcap_writes_an_odometry_message_per_trajectory_row(tmp_path: Path) -> None:
    from collections import Counter

    from mcap.reader import make_reader

    root = Path(__file__).resolve().parents[2]
    cli = "import sys\n" + CLI
    done = subprocess.run([sys.executable, "-c", cli, "simulate", str(root / "missions" / "field_transit.yaml"),
                           "--out", str(tmp_path / "run"), "--no-plots", "-q", "--mcap"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    with (tmp_path / "run" / "run.mcap").open("rb") as f:
        topics = Counter(ch.topic for _, ch, _ in make_reader(f).iter_messages())
    rows = len((tmp_path / "run" / "trajectory.csv").read_text().splitlines()) - 1
    assert rows > 1000 and topics["/odometry/estimated"] == topics["/odometry/true"] == rows
    assert topics["/rosout"] >= 12  # every element started and finished, the mission started and finished
