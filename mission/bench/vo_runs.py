"""Running visual odometers side by side for the VO benchmark: every frame fed once to each odometer (CPU time
per odometer), and their poses scored against the ground truth (`mission.trajectory_eval`)."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from typing import Any

import numpy as np

EFFECTIVE_STEPS = (2, 4, 8, 16)
PHASES = 4          # robustness: the odometers also started 1 … PHASES - 1 frames late (not with --quick)


def errors(gt: np.ndarray, est: np.ndarray) -> dict[str, Any]:
    from mission.trajectory_eval import evaluate

    e = evaluate(gt, est)
    anchored = np.linalg.norm(est[:, :3, 3] - gt[:, :3, 3], axis=1)
    return {"mean_error_m": round(float(anchored.mean()), 4), "end_error_m": round(float(anchored[-1]), 4),
            "ate_rmse_m": round(e.ate_rmse_m, 4), "rpe_trans_rmse_m": round(e.rpe_trans_rmse_m, 4),
            "rpe_rot_rmse_deg": round(e.rpe_rot_rmse_deg, 4), "endpoint_drift_m": round(e.endpoint_drift_m, 4),
            "endpoint_drift_percent": round(e.endpoint_drift_percent, 3), "path_length_m": round(e.path_length_m, 2)}


def relative(poses: np.ndarray) -> np.ndarray:
    from mission.geometry import invert

    return np.stack([invert(poses[0]) @ P for P in poses])


def lockstep(frames: Iterable[Any], specs: dict[str, tuple[str, dict[str, Any]]],
              views: dict[str, Callable[[int, Any], Any]] | None = None) -> dict[str, Any]:
    """Feed every frame once to one odometer per spec (through the spec's `views` entry, when it has one: what that
    odometer sees of frame i, None for nothing); poses of all frames, CPU seconds and stats per spec."""
    from perception_plugins.vo import Odometer, settings_for
    from perception_plugins.vo.se3 import fill_poses

    odometers = {name: Odometer(settings_for(method, **options)) for name, (method, options) in specs.items()}
    known: dict[str, dict[int, np.ndarray]] = {name: {} for name in specs}
    cpu = dict.fromkeys(specs, 0.0)
    count = 0
    for i, frame in enumerate(frames):
        count = i + 1
        for name, od in odometers.items():
            seen = views[name](i, frame) if views and name in views else frame
            if seen is None:
                continue
            t0 = time.process_time()
            for e in od.push(i, seen):
                known[name][e.index] = e.T_origin_cam
            cpu[name] += time.process_time() - t0
    out: dict[str, Any] = {}
    for name, od in odometers.items():
        t0 = time.process_time()
        for e in od.finish():
            known[name][e.index] = e.T_origin_cam
        cpu[name] += time.process_time() - t0
        s = od.stats
        out[name] = {"poses": fill_poses(known[name], count), "cpu_s": cpu[name], "positions": s.positions,
                     "losses": s.losses, "halvings": s.halvings, "fragments": s.fragments, "bindings": s.bindings,
                     "references": len(od.network.references) if od.network is not None else 0,
                     "references_used": len(od.network.used) if od.network is not None else 0}
    return out


def table1_specs(fps: float) -> dict[str, tuple[str, dict[str, Any]]]:
    specs: dict[str, tuple[str, dict[str, Any]]] = {}
    for e in EFFECTIVE_STEPS:
        specs[f"classic_{e}"] = ("classic", {"step": e})
        specs[f"klt_{e}"] = ("klt", {"step": 2, "fragment_steps": e // 2})
    specs["adaptive"] = ("adaptive", {"fps": fps, "max_step": 64})
    return specs


def summarise(runs: dict[str, Any], gt: np.ndarray, frames: int) -> dict[str, Any]:
    table: dict[str, Any] = {}
    for name, r in runs.items():
        table[name] = {**errors(gt, r["poses"]), "positions": r["positions"], "losses": r["losses"],
                       "halvings": r["halvings"], "fragments": r["fragments"],
                       "ms_per_frame_cpu": round(1e3 * r["cpu_s"] / frames, 2)}
        if r["references"]:
            table[name].update(bindings=r["bindings"], references=r["references"],
                               references_used=r["references_used"])
    return table


__all__ = ["EFFECTIVE_STEPS", "PHASES", "errors", "lockstep", "relative", "summarise", "table1_specs"]
