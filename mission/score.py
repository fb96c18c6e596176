"""`auv score RUN_DIR --truth DIR`: score an `auv run` against the truth that `auv sim serve --out DIR` kept.

The simulator's true trajectory is sampled at the run's own times (both are the vehicle's clock), the run's
`trajectory.csv` gets its true columns, and its `metrics.json` gets the figures `auv simulate` reports under the
same keys (`navigation`, each element's `path_length_m`, `min_altitude_m`, `end_position_error_m`,
`distance_m`, `seabed_contacts`), computed by the same functions (`mission.scoring`).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from mission.errors import RunFolderError
from mission.events import read_events
from mission.runfolder import TRAJECTORY_COLUMNS, check_complete, read_csv, write_metrics, write_trajectory
from mission.scoring import ElementSpan, navigation_errors, path_length, resample, track_metrics

CONTACT_ALTITUDE_M = 1e-3  # the simulator clamps the vehicle onto the seabed: a true altitude this low is contact


def element_spans(events: list[dict[str, Any]]) -> dict[str, ElementSpan]:
    """Each element's start and end on the vehicle's clock (from the event log), and a transit's goal."""
    spans: dict[str, ElementSpan] = {}
    started: dict[str, tuple[float, tuple[float, float] | None]] = {}
    for e in events:
        name = e.get("element")
        if e.get("event") == "element_started" and name:
            path = e.get("planned_path") or []
            goal = (float(path[-1][0]), float(path[-1][1])) if path and e.get("kind") != "survey" else None
            started[name] = (float(e["time"]), goal)
        elif e.get("event") in ("element_finished", "element_failed") and name in started:
            t0, goal = started.pop(name)
            kind = e.get("kind")
            spans[name] = ElementSpan(name, t0, float(e["time"]), goal if kind == "transit" else None)
    return spans


def score_run(run_dir: str | Path, truth_dir: str | Path) -> dict[str, Any]:
    """Score the run folder against the truth folder; rewrites its trajectory.csv and metrics.json and returns
    the metrics."""
    run_dir, truth_dir = Path(run_dir), Path(truth_dir)
    check_complete(run_dir)
    for folder, name in ((run_dir, "metrics.json"), (run_dir, "trajectory.csv"), (run_dir, "events.jsonl"),
                         (truth_dir, "trajectory.csv")):
        if not (folder / name).is_file():
            raise RunFolderError(f"{folder}: missing {name}")
    run, run_text = read_csv(run_dir / "trajectory.csv", ("element",))
    truth, _ = read_csv(truth_dir / "trajectory.csv", ("element",))
    if not len(truth.get("time", [])):
        raise RunFolderError(f"{truth_dir}/trajectory.csv holds no rows")
    t_run, t_true = run["time"], truth["time"]
    inside = (t_run >= t_true[0]) & (t_run <= t_true[-1])
    if not inside.any():
        raise RunFolderError(f"the run's times ({t_run[0]:.1f}–{t_run[-1]:.1f} s) do not overlap the truth's "
                             f"({t_true[0]:.1f}–{t_true[-1]:.1f} s): is {truth_dir} this run's simulator?")
    t = t_run[inside]
    true = {c: resample(t_true, t, truth[c], angle=(c == "heading")) for c in ("north", "east", "depth", "heading",
                                                                               "altitude")}
    est = {c: run[c][inside] for c in ("north_est", "east_est", "depth_est")}
    metrics: dict[str, Any] = json.loads((run_dir / "metrics.json").read_text(encoding="utf-8"))
    navigation = navigation_errors(true["north"], true["east"], true["depth"], est["north_est"], est["east_est"],
                                   est["depth_est"])
    if (truth_dir / "usbl.csv").is_file():
        fixes, _ = read_csv(truth_dir / "usbl.csv")
        used = fixes.get("used", np.zeros(0)) > 0.5
        in_run = (fixes.get("time", np.zeros(0)) >= t[0]) & (fixes.get("time", np.zeros(0)) <= t[-1])
        navigation["usbl_fixes"] = int((used & in_run).sum())
        navigation["usbl_rejected"] = int((used & in_run & (fixes.get("accepted", np.zeros(0)) < 0.5)).sum())
    metrics["navigation"] = navigation
    spans = element_spans(read_events(run_dir / "events.jsonl"))
    for item in metrics.get("elements", []):
        span = spans.get(item.get("id"))
        if span is not None:
            item.update(track_metrics(span, t, true["north"], true["east"], true["altitude"]))
    window = (t_true >= t[0]) & (t_true <= t[-1])
    metrics["distance_m"] = round(path_length(truth["north"][window], truth["east"][window],
                                              truth["depth"][window]), 2)
    metrics["seabed_contacts"] = int((truth["altitude"][window] <= CONTACT_ALTITUDE_M).sum())
    metrics["scored"] = True
    metrics["truth"] = str(truth_dir)
    write_metrics(run_dir, metrics)
    rows = []
    index = np.cumsum(inside) - 1  # row k of the run is row index[k] of the truth sampled at the run's times
    for k in range(len(t_run)):
        row: list[object] = [float(run[c][k]) for c in TRAJECTORY_COLUMNS[:-1]]
        if inside[k]:
            row[1:6] = [float(true[c][index[k]]) for c in ("north", "east", "depth", "heading", "altitude")]
        rows.append((*row, run_text["element"][k]))
    write_trajectory(run_dir, rows)
    return metrics
