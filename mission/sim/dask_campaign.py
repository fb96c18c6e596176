"""Campaign runs on Dask (`auv simulate MISSION --seeds … --dask [SCHEDULER_ADDRESS]`): each seeded run is a
Dask task on a worker process, its row gathered back to the client, which writes `campaign.json` as rows arrive,
exactly as the local-process executor does (`mission.sim.campaign`).

- With no address a `LocalCluster` of `jobs` single-threaded worker processes is started (and stopped at the end);
  with one, the tasks go to a running `dask scheduler` whose workers may sit on other machines. The workers must
  have the project installed, and the mission (and its world) at the same path.
- Each worker writes its run folder where the campaign's `--out` points. On a path every machine shares (NFS, a
  cluster file system) the campaign folder then holds every run folder, as locally. Without a shared path the
  rows still come back to the client and `campaign.json` is complete; the run folders stay on the workers' disks.
- A worker that dies mid-run (killed, out of memory) has its task retried once on another worker (the local
  cluster's `distributed.scheduler.allowed-failures` is 1; a remote scheduler applies its own setting), then the
  run is recorded as failed, never lost.
- Ctrl-C cancels the tasks still queued, closes the client (and the local cluster), and re-raises.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from mission.errors import AuvError

Runner = Callable[..., dict[str, Any]]


def dask_rows(runner: Runner, mission_path: str, seeds: Sequence[int], out_dir: Path, plots: bool,
              plugin_latency_s: float | None, record: Callable[[dict[str, Any]], None], address: str | None,
              jobs: int) -> None:
    """Run `runner(mission_path, seed, folder, plots, plugin_latency_s)` for every seed on Dask, handing each row
    to `record` as it arrives."""
    try:
        import dask
        from distributed import Client, KilledWorker, LocalCluster, as_completed
    except ImportError:
        raise AuvError("--dask needs Dask: pip install 'auv-mission[campaigns]'") from None
    cluster: Any = None
    with dask.config.set({"distributed.scheduler.allowed-failures": 1}):
        try:
            if address is None:
                cluster = LocalCluster(n_workers=max(1, jobs), threads_per_worker=1, processes=True,
                                       dashboard_address=None)
                client = Client(cluster)
            else:
                client = Client(address, timeout=30)
        except OSError as exc:
            if cluster is not None:
                cluster.close()
            raise AuvError(f"--dask: cannot reach the scheduler at {address} ({exc})") from None
    futures = {client.submit(runner, mission_path, seed, str(out_dir / f"seed-{seed}"), plots, plugin_latency_s,
                             key=f"auv-{out_dir.name}-seed-{seed}", pure=False): seed for seed in seeds}
    try:
        for future in as_completed(futures):
            seed = futures[future]
            try:
                row = future.result()
            except KilledWorker as exc:
                row = {"seed": seed, "error": f"its worker died twice ({exc}); {out_dir / f'seed-{seed}'} may be "
                                              "incomplete"}
            except Exception as exc:  # noqa: BLE001 - a task that raised is one failed run, recorded
                row = {"seed": seed, "error": f"{type(exc).__name__}: {exc}"}
            record(row)
    except BaseException:
        client.cancel(list(futures))
        raise
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
