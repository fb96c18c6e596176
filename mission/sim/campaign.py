"""Many seeded runs of one mission (`auv simulate MISSION --seeds 1-20`): how the mission holds up.

Each seed runs in its own process (`jobs` at a time) into `OUT/seed-N/`, a full run folder; `OUT/campaign.json`
is rewritten as each run ends (a run that crashes is recorded with its error, the others go on), with a row per
run (`run_summary`) and the aggregate (`aggregate`): completion rate, each element's success rate, and the worst
figure each element kind reports (coverage, surface observed, targets photographed, camera error, altitude).
"""

from __future__ import annotations

import json
import multiprocessing
import os
import re
import traceback
from collections.abc import Callable, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from pathlib import Path
from typing import Any

from mission.errors import AuvError
from mission.plugin_calls import SIMULATED_LATENCY_S

_RANGE = re.compile(r"^\s*(-?\d+)\s*(?:-\s*(-?\d+))?\s*$")


def parse_seeds(text: str) -> list[int]:
    """Seeds from `"1-5"`, `"3,7,9"` or a mix (`"1-3,10"`), in order, without repeats.

    >>> parse_seeds("1-3,10,2")
    [1, 2, 3, 10]
    """
    seeds: list[int] = []
    for part in text.split(","):
        m = _RANGE.match(part)
        if m is None:
            raise AuvError(f"--seeds: '{part.strip()}' is not a seed or a range such as 1-20")
        lo = int(m.group(1))
        hi = int(m.group(2)) if m.group(2) is not None else lo
        if hi < lo:
            raise AuvError(f"--seeds: range '{part.strip()}' runs backwards")
        seeds.extend(s for s in range(lo, hi + 1) if s not in seeds)
    if not seeds:
        raise AuvError("--seeds names no seed")
    return seeds


def _element_figures(e: dict[str, Any]) -> dict[str, Any]:
    """The figures of one element that say whether it did its job (by kind)."""
    out: dict[str, Any] = {"status": e["status"]}
    if "min_altitude_m" in e:
        out["min_altitude_m"] = e["min_altitude_m"]
    kind = e["kind"]
    if kind == "survey":
        out.update(coverage_percent=e.get("coverage_percent"), false_alarms=e.get("false_alarms"),
                   missed=len(e.get("missed", [])))
    elif kind == "explore":
        out.update(surface_observed_percent=e.get("surface_observed_percent"),
                   min_distance_to_object_m=e.get("min_distance_to_object_m"),
                   safe_distance_breached=e.get("safe_distance_breached"))
    elif kind == "inspect":
        targets = e.get("targets", {})
        errors = [t["camera_error_max_m"] for t in targets.values() if t.get("camera_error_max_m") is not None]
        out.update(targets=len(targets), targets_ok=e.get("targets_ok", 0),
                   camera_error_max_m=max(errors, default=None),
                   target_in_every_photo=all(t.get("target_in_every_photo", False) for t in targets.values()
                                             if t.get("photos")),
                   replans=len(e.get("replans", [])) if isinstance(e.get("replans"), list) else e.get("replans"))
    elif kind == "reference":
        out.update(recognised=e.get("recognised"))
    return out


def run_summary(metrics: dict[str, Any]) -> dict[str, Any]:
    """One run's row: outcome, times, safety, and each element's figures."""
    return {
        "seed": metrics["seed"],
        "completed": metrics["completed"],
        "aborted": metrics["aborted"],
        "abort_reason": metrics.get("abort_reason"),
        "mission_time_s": metrics["mission_time_s"],
        "wall_time_s": metrics["wall_time_s"],
        "safety_violations": len(metrics.get("safety_violations", [])),
        "seabed_contacts": metrics.get("seabed_contacts", 0),
        "navigation_error_max_m": metrics["navigation"]["position_error_max_m"],
        "elements": {e["id"]: {"kind": e["kind"], **_element_figures(e)} for e in metrics["elements"]},
    }


_WORST = {  # figure → whether the worst is the lowest (True) or the highest (False)
    "coverage_percent": True, "surface_observed_percent": True, "min_distance_to_object_m": True,
    "targets_ok": True, "min_altitude_m": True, "camera_error_max_m": False, "false_alarms": False, "missed": False,
}


def aggregate(rows: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """Completion rate, per-element success rate and the worst of each figure over the runs that finished."""
    done = [r for r in rows if "error" not in r]
    out: dict[str, Any] = {
        "runs": len(rows),
        "crashed": len(rows) - len(done),
        "completed": sum(1 for r in done if r["completed"]),
        "aborted": sum(1 for r in done if r["aborted"]),
        "completed_percent": round(100.0 * sum(1 for r in done if r["completed"]) / len(rows), 1) if rows else 0.0,
        "safety_violations": sum(r["safety_violations"] for r in done),
        "seabed_contacts": sum(r["seabed_contacts"] for r in done),
        "failed_seeds": [r["seed"] for r in rows if "error" in r or not r["completed"]],
        "elements": {},
    }
    ids: list[str] = []
    for r in done:
        ids.extend(i for i in r["elements"] if i not in ids)
    for ident in ids:
        runs = [r["elements"][ident] for r in done if ident in r["elements"]]
        entry: dict[str, Any] = {"kind": runs[0]["kind"], "runs": len(runs),
                                 "succeeded": sum(1 for e in runs if e["status"] == "succeeded")}
        for key, lowest in _WORST.items():
            values = [e[key] for e in runs if e.get(key) is not None]
            if values:
                entry[f"worst_{key}"] = min(values) if lowest else max(values)
        out["elements"][ident] = entry
    return out


def _run_one(mission_path: str, seed: int, out: str, plots: bool,
             plugin_latency_s: float | None = SIMULATED_LATENCY_S) -> dict[str, Any]:
    """Worker: one seeded run into its own folder; the summary row, or the error that stopped it."""
    from mission.language import load_mission
    from mission.sim.run import simulate

    try:
        result = simulate(load_mission(mission_path), seed=seed, out=out, plots=plots,
                          plugin_latency_s=plugin_latency_s)
    except Exception as exc:  # noqa: BLE001 - one crashed run must not end the campaign; it is recorded
        return {"seed": seed, "error": f"{type(exc).__name__}: {exc}", "traceback": traceback.format_exc()}
    return run_summary(result.metrics)


def run_campaign(mission_path: str | Path, seeds: Sequence[int], out: str | Path, jobs: int = 1,
                 plots: bool = False, on_run: Callable[[dict[str, Any]], None] | None = None,
                 plugin_latency_s: float | None = SIMULATED_LATENCY_S, dask: str | None = None) -> dict[str, Any]:
    """Run `mission_path` once per seed (`jobs` processes at a time) into `out/seed-N/`; returns and writes
    `out/campaign.json` (rewritten after every run). With `dask` the runs are Dask tasks
    (`mission.sim.dask_campaign`): "" starts a local cluster of `jobs` workers, an address uses that scheduler."""
    out_dir = Path(out)
    out_dir.mkdir(parents=True, exist_ok=True)
    rows: list[dict[str, Any]] = []
    report_path = out_dir / "campaign.json"

    def record(row: dict[str, Any]) -> None:
        rows.append(row)
        rows.sort(key=lambda r: r["seed"])
        report = {"mission": str(mission_path), "seeds": list(seeds), "summary": aggregate(rows), "runs": rows}
        tmp = report_path.with_suffix(".tmp")
        tmp.write_text(json.dumps(report, indent=1))
        os.replace(tmp, report_path)
        if on_run is not None:
            on_run(row)

    jobs = max(1, min(jobs, len(seeds)))
    if dask is not None:
        from mission.sim.dask_campaign import dask_rows

        dask_rows(_run_one, str(mission_path), seeds, out_dir, plots, plugin_latency_s, record, dask or None, jobs)
    elif jobs == 1:
        for seed in seeds:
            record(_run_one(str(mission_path), seed, str(out_dir / f"seed-{seed}"), plots, plugin_latency_s))
    else:
        # spawn: a forked child would inherit the parent's MuJoCo/OpenGL state
        ctx = multiprocessing.get_context("spawn")
        with ProcessPoolExecutor(max_workers=jobs, mp_context=ctx) as pool:
            pending: set[Future[dict[str, Any]]] = {
                pool.submit(_run_one, str(mission_path), s, str(out_dir / f"seed-{s}"), plots, plugin_latency_s)
                for s in seeds}
            while pending:
                finished, pending = wait(pending, return_when=FIRST_COMPLETED)
                for f in finished:
                    record(f.result())
    report: dict[str, Any] = json.loads(report_path.read_text())
    return report
