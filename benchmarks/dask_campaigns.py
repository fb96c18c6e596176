"""Issue 24's campaign figures, measured with the real components a user starts.

    python benchmarks/dask_campaigns.py identity MISSION --seeds 1-200 --out DIR
        the same campaign through `auv simulate --jobs 2` (local processes) and `--dask --jobs 2` (a LocalCluster of
        two workers); prints whether the campaign.json rows are identical, wall times aside.

    python benchmarks/dask_campaigns.py kill MISSION --seeds 1-40 --out DIR
        starts `dask scheduler` and two `dask worker` processes from the command line on loopback, runs
        `auv simulate --dask ADDRESS`, kills one worker (SIGKILL) once a quarter of the runs are done, and prints
        how many runs completed, failed or are missing.

Both write a JSON summary to DIR/summary-*.json."""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

BIN = Path(sys.executable).parent
WALL = ("wall_time_s",)


def _rows(campaign: Path) -> list[dict[str, Any]]:
    report = json.loads((campaign / "campaign.json").read_text())
    return [{k: v for k, v in row.items() if k not in WALL} for row in report["runs"]]


def _simulate(mission: str, seeds: str, out: Path, *extra: str) -> float:
    start = time.monotonic()
    subprocess.run([str(BIN / "auv"), "simulate", mission, "--seeds", seeds, "--out", str(out), "--no-plots",
                    "--force", "-q", *extra], check=True)
    return time.monotonic() - start


def identity(mission: str, seeds: str, out: Path) -> dict[str, Any]:
    local_s = _simulate(mission, seeds, out / "local", "--jobs", "2")
    dask_s = _simulate(mission, seeds, out / "dask", "--jobs", "2", "--dask")
    local, dask = _rows(out / "local"), _rows(out / "dask")
    differing = [a["seed"] for a, b in zip(local, dask, strict=False) if a != b]
    return {"mission": mission, "seeds": seeds, "runs": len(local), "runs_dask": len(dask),
            "identical": local == dask, "differing_seeds": differing,
            "completed": sum(bool(r.get("completed")) for r in local),
            "wall_s": {"jobs_2": round(local_s, 1), "local_cluster_2": round(dask_s, 1)}}


def _wait_for(path: Path, timeout_s: float) -> None:
    deadline = time.monotonic() + timeout_s
    while not path.is_file():
        if time.monotonic() > deadline:
            raise TimeoutError(f"{path} did not appear within {timeout_s:g} s")
        time.sleep(0.2)


def kill(mission: str, seeds: str, out: Path) -> dict[str, Any]:
    out.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, "DASK_DISTRIBUTED__WORKER__DAEMON": "False"}
    scheduler_file = out / "scheduler.json"
    scheduler_file.unlink(missing_ok=True)
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, "env": env}
    scheduler = subprocess.Popen([str(BIN / "dask"), "scheduler", "--host", "127.0.0.1", "--port", "0",
                                  "--no-dashboard", "--scheduler-file", str(scheduler_file)], **quiet)
    workers: list[subprocess.Popen[bytes]] = []
    try:
        _wait_for(scheduler_file, 60)
        address = json.loads(scheduler_file.read_text())["address"]
        for _ in range(2):
            workers.append(subprocess.Popen([str(BIN / "dask"), "worker", address, "--nworkers", "1",
                                             "--nthreads", "1", "--no-dashboard"], start_new_session=True, **quiet))
        campaign = out / "campaign"
        start = time.monotonic()
        auv = subprocess.Popen([str(BIN / "auv"), "simulate", mission, "--seeds", seeds, "--dask", address,
                                "--out", str(campaign), "--no-plots", "--force", "-q"])
        total = len(_expand(seeds))
        killed_at = None
        while auv.poll() is None:
            time.sleep(0.5)
            done = _done(campaign)
            if killed_at is None and done >= max(1, total // 4):
                os.killpg(workers[0].pid, signal.SIGKILL)  # the worker and its nanny, as a machine lost
                killed_at = done
        rows = _rows(campaign)
        return {"mission": mission, "seeds": seeds, "exit_code": auv.returncode, "killed_after_runs": killed_at,
                "runs": len(rows), "completed": sum(bool(r.get("completed")) for r in rows),
                "failed": [r["seed"] for r in rows if r.get("error")],
                "missing": sorted(set(_expand(seeds)) - {r["seed"] for r in rows}),
                "wall_s": round(time.monotonic() - start, 1)}
    finally:
        for process in (*workers, scheduler):
            if process.poll() is None:
                process.terminate()
                try:
                    process.wait(20)
                except subprocess.TimeoutExpired:
                    process.kill()


def _done(campaign: Path) -> int:
    try:
        return len(json.loads((campaign / "campaign.json").read_text())["runs"])
    except (OSError, ValueError, KeyError):
        return 0


def _expand(seeds: str) -> list[int]:
    first, _, last = seeds.partition("-")
    return list(range(int(first), int(last or first) + 1))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("what", choices=("identity", "kill"))
    parser.add_argument("mission")
    parser.add_argument("--seeds", default="1-200")
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    summary = (identity if args.what == "identity" else kill)(args.mission, args.seeds, args.out)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / f"summary-{args.what}.json").write_text(json.dumps(summary, indent=1))
    print(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main()
