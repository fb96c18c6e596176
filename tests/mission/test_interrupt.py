"""Interrupted runs, with real processes and real signals: SIGINT and SIGTERM end `auv simulate` cleanly with a
complete, marked folder (exit 130/143); after `kill -9` the readers say the folder is incomplete in one line; a
closed pipe gives no traceback."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import WORLD

from mission.runfolder import read_csv

LAP = """
  - {{id: n{k}, transit: {{to: {{north: 250, east: 0}}, depth: 30}}}}
  - {{id: e{k}, transit: {{to: {{north: 250, east: 350}}, depth: 30}}}}
  - {{id: s{k}, transit: {{to: {{north: 0, east: 350}}, depth: 30}}}}
  - {{id: w{k}, transit: {{to: {{north: 0, east: 0}}, depth: 30}}}}"""


@pytest.fixture
def long_mission(tmp_path: Path) -> Path:
    """Forty laps of a box: far longer than any test waits (each lap is ~1,000 s simulated)."""
    path = tmp_path / "long.yaml"
    path.write_text(f"""name: long
world: {WORLD}
sensors: {{usbl: {{sigma: 1.5, rate_hz: 0.5}}}}
safety: {{max_duration: 20h, energy_reserve: 1%, geofence: [[-60, -60], [-60, 460], [360, 460], [360, -60]]}}
vehicle: {{energy_wh: 100000}}
route:{"".join(LAP.format(k=k) for k in range(40))}
""", encoding="utf-8")
    return path


def start(mission: Path, out: Path) -> subprocess.Popen[str]:
    proc = subprocess.Popen([sys.executable, "-m", "mission", "simulate", str(mission), "--out", str(out), "-q",
                             "--no-plots"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60.0
    while time.monotonic() < deadline:  # running: the trajectory has rows on disk (streamed, flushed every second)
        rows = (out / "trajectory.csv").read_text().count("\n") if (out / "trajectory.csv").is_file() else 0
        if rows > 10:
            return proc
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.1)
    proc.kill()
    raise AssertionError("the run never wrote its trajectory")


@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_ends_the_run_cleanly_with_a_marked_folder_and_its_exit_code(long_mission, tmp_path, sig, code):
    out = tmp_path / "run"
    proc = start(long_mission, out)
    proc.send_signal(sig)
    stdout, stderr = proc.communicate(timeout=60)
    assert proc.returncode == code, stderr
    assert "Traceback" not in stderr and "INTERRUPTED" in stdout
    events = [json.loads(line) for line in (out / "events.jsonl").read_text().splitlines()]
    assert [e["event"] for e in events[-2:]] == ["interrupted", "mission_finished"]
    assert events[-2]["signal"] == sig.name
    assert not any(e.get("completed") for e in events)  # never `completed: true` for a run cut short
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["interrupted"] is True and metrics["completed"] is False and metrics["signal"] == sig.name
    traj, _ = read_csv(out / "trajectory.csv", ("element",))
    # the trajectory runs to the moment the run stopped, and the metrics cover the same time
    assert traj["time"][-1] == pytest.approx(events[-1]["time"], abs=0.21)
    assert metrics["mission_time_s"] == pytest.approx(traj["time"][-1], abs=0.5)
    assert not np.isnan(traj["north"]).any()


def test_after_kill_9_the_readers_say_incomplete_in_one_line(long_mission, tmp_path):
    out = tmp_path / "run"
    proc = start(long_mission, out)
    proc.kill()
    proc.wait(timeout=30)
    assert not (out / "metrics.json").exists()
    for argv in (["plot", str(out)], ["score", str(out), "--truth", str(out)]):
        run = subprocess.run([sys.executable, "-m", "mission", *argv], capture_output=True, text=True, timeout=60)
        assert run.returncode == 1
        assert run.stderr.strip() == f"auv: {out}: incomplete run folder (no metrics.json: the run was killed, or " \
                                     "is still running)"
    # the lock went with the process: the folder can be claimed again, and replaced
    from mission.runlock import claim_run_folder

    with claim_run_folder(out, "test", force=True):
        assert [p.name for p in out.iterdir()] == [".auv-run"]


def test_a_closed_pipe_gives_no_traceback():
    read_end, write_end = os.pipe()
    proc = subprocess.Popen([sys.executable, "-m", "mission", "schema"], stdout=write_end, stderr=subprocess.PIPE)
    os.close(write_end)
    os.close(read_end)  # the reader is gone before the first line, as `| head -0` would be
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 141
    assert err.decode() == ""
