"""Campaigns on Dask: a LocalCluster and a scheduler with a worker started as a user starts them (`dask
scheduler`, `dask worker` on loopback) give the same campaign.json as local processes, wall times aside; a worker
that dies mid-run is retried once, then the run is recorded as failed."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import MISSIONS

pytest.importorskip("distributed")

from mission.sim.campaign import run_campaign  # noqa: E402
from mission.sim.dask_campaign import dask_rows  # noqa: E402

MISSION = MISSIONS / "field_transit.yaml"
WALL = ("wall_time_s",)


def rows_without_wall_times(report: dict) -> list[dict]:
    return [{k: v for k, v in row.items() if k not in WALL} for row in report["runs"]]


def test_a_four_seed_campaign_on_a_local_cluster_equals_local_processes(tmp_path):
    seeds = [1, 2, 3, 4]
    local = run_campaign(MISSION, seeds, tmp_path / "local", jobs=2)
    dask = run_campaign(MISSION, seeds, tmp_path / "dask", jobs=2, dask="")
    assert rows_without_wall_times(dask) == rows_without_wall_times(local)
    assert dask["summary"]["completed"] == 4
    for seed in seeds:
        assert (tmp_path / "dask" / f"seed-{seed}" / "metrics.json").is_file()
    assert json.loads((tmp_path / "dask" / "campaign.json").read_text())["summary"] == dask["summary"]


def test_a_run_whose_worker_dies_is_retried_once_then_recorded_as_failed(tmp_path):
    attempts = tmp_path / "attempts"
    attempts.mkdir()

    def dies_on_seed_2(mission, seed, folder, plots, latency):
        (attempts / f"{seed}-{os.getpid()}").touch()
        if seed == 2:
            os._exit(3)  # the worker process dies, as when killed or out of memory
        return {"seed": seed, "completed": True}

    rows: list[dict] = []
    dask_rows(dies_on_seed_2, str(MISSION), [1, 2, 3], tmp_path, False, None, rows.append, None, 2)
    by_seed = {r["seed"]: r for r in rows}
    assert sorted(by_seed) == [1, 2, 3]
    assert by_seed[1]["completed"] and by_seed[3]["completed"]
    assert "worker died" in by_seed[2]["error"]
    assert len(list(attempts.glob("2-*"))) == 2  # tried, then retried once


def test_a_scheduler_and_worker_started_as_a_user_starts_them_run_the_campaign(tmp_path):
    bin_dir = Path(sys.executable).parent
    scheduler_file = tmp_path / "scheduler.json"
    env = {**os.environ, "DASK_DISTRIBUTED__WORKER__DAEMON": "False"}
    scheduler = subprocess.Popen([str(bin_dir / "dask"), "scheduler", "--host", "127.0.0.1", "--port", "0",
                                  "--no-dashboard", "--scheduler-file", str(scheduler_file)],
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    worker = None
    try:
        deadline = time.monotonic() + 60
        while not scheduler_file.is_file() and time.monotonic() < deadline:
            time.sleep(0.2)
        address = json.loads(scheduler_file.read_text())["address"]
        worker = subprocess.Popen([str(bin_dir / "dask"), "worker", address, "--nworkers", "1", "--nthreads", "1",
                                   "--no-dashboard"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
        out = subprocess.run([str(bin_dir / "auv"), "simulate", str(MISSION), "--seeds", "1-2", "--dask", address,
                              "--out", str(tmp_path / "campaign"), "--no-plots"],
                             capture_output=True, text=True, timeout=240)
        assert out.returncode == 0, out.stdout + out.stderr
        report = json.loads((tmp_path / "campaign" / "campaign.json").read_text())
        assert report["summary"]["completed"] == 2 and [r["seed"] for r in report["runs"]] == [1, 2]
    finally:
        for process in (worker, scheduler):
            if process is not None:
                process.terminate()
                try:
                    process.wait(20)
                except subprocess.TimeoutExpired:
                    process.kill()
