"""Issue 22's loop, measured: how well a mission that knows an object only from `auv reconstruct`'s database entry
photographs the targets the designer named, against where those targets truly are.

The designer names a target by its true world position (`--target NAME=N,E,D`); the entry holds it in the entry's
object frame, and an `inspect` element plans each photograph's viewpoint in that frame. The photograph is right
when the camera truly stands where the viewpoint puts it relative to the *true* target: the viewpoint's offset
from the target (object frame, turned into the world by the entry's heading) added to the target's true world
position. `photo_errors` measures that distance from the run folder (`metrics.json`'s photographs and
`trajectory.csv`'s true poses), so the figure holds every error of the loop at once: the reconstruction's (the
entry frame against the world), the referencing's, the odometry's and the control's.
"""

from __future__ import annotations

import csv
import json
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from mission.frames import camera_pose, rotation_zyx
from mission.reconstruct import ReconstructionError


def _true_poses(run_dir: Path) -> tuple[np.ndarray, np.ndarray]:
    """Times and true (north, east, depth, heading) of every row of the run's trajectory."""
    with (run_dir / "trajectory.csv").open(encoding="utf-8") as f:
        rows = [(float(r["time"]), float(r["north"]), float(r["east"]), float(r["depth"]), float(r["heading"]))
                for r in csv.DictReader(f)]
    table = np.array(rows, dtype=float)
    return table[:, 0], table[:, 1:]


def photo_errors(run_dir: Path, element_id: str, entry: Mapping[str, Any],
                 targets_world: Mapping[str, Sequence[float]], baseline: float) -> list[dict[str, Any]]:
    """One row per photograph of the inspect element `element_id`: its target, the true camera's distance from
    the viewpoint placed on the target's true world position (`error_m`), and how far off the optical axis the true
    target is (`target_off_axis`: the tangent of its angle from the axis; 0 is the image centre). `entry` is the
    database entry the mission used (for its heading and its targets' object-frame positions); `baseline` the
    stereo baseline (the left camera is the one photographed with)."""
    metrics = json.loads((run_dir / "metrics.json").read_text(encoding="utf-8"))
    element = next((e for e in metrics["elements"] if e["id"] == element_id), None)
    if element is None:
        raise ReconstructionError(f"{run_dir}: no element '{element_id}' in metrics.json")
    R_world_object = rotation_zyx(float(entry["pose"].get("heading", 0.0)), 0.0, 0.0)
    at_object = {t["id"]: np.asarray(t["at"], dtype=float) for t in entry.get("targets", [])}
    times, poses = _true_poses(run_dir)
    out = []
    for photo in element.get("photos", []):
        name = photo["target"]
        if name not in targets_world or name not in at_object:
            continue
        k = int(np.argmin(np.abs(times - float(photo["time"]))))
        north, east, down, heading = (float(v) for v in poses[k])
        T_world_cam = camera_pose(north, east, down, heading, baseline=baseline)
        offset = R_world_object @ (np.asarray(photo["viewpoint_object"], dtype=float) - at_object[name])
        target = np.asarray(targets_world[name], dtype=float)
        error = float(np.linalg.norm(T_world_cam[:3, 3] - (target + offset)))
        p_cam = T_world_cam[:3, :3].T @ (target - T_world_cam[:3, 3])
        lateral = float(np.linalg.norm(p_cam[:2]) / p_cam[2]) if p_cam[2] > 0 else float("inf")
        out.append({"target": name, "time": float(photo["time"]), "error_m": round(error, 4),
                    "target_off_axis": round(lateral, 4)})
    return out


def mesh_offset(vertices: np.ndarray, sdf: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
    """The translation that best lays the reconstructed object's vertices (world, the explore run's navigation
    frame) on the true surface (`sdf`: signed distance to the true geometry): least squares on the distances,
    robust (soft L1, 5 cm scale). It is the navigation error the reconstruction inherited, as one offset."""
    from scipy.optimize import least_squares

    fit = least_squares(lambda t: sdf(vertices - t), np.zeros(3), loss="soft_l1", f_scale=0.05, x_scale=0.1)
    return np.asarray(fit.x, dtype=float)


def recognitions(run_dir: Path, element_id: str) -> dict[str, dict[str, int]]:
    """Per characteristic-point set: the referencing attempts of the element that asked for it (`attempts`, the
    fused records left out) and the attempts that recognised it (`recognised`), from `metrics.json`."""
    metrics = json.loads((run_dir / "metrics.json").read_text(encoding="utf-8"))
    element = next((e for e in metrics["elements"] if e["id"] == element_id), None)
    if element is None:
        raise ReconstructionError(f"{run_dir}: no element '{element_id}' in metrics.json")
    counts: dict[str, dict[str, int]] = {}
    for attempt in element.get("attempts", []):
        if attempt.get("stage") == "fused":
            continue
        counts.setdefault(str(attempt.get("set")), {"recognised": 0, "attempts": 0})["attempts"] += 1
        if attempt.get("recognised") and not attempt.get("ambiguous") and attempt.get("recognised_set") is not None:
            counts.setdefault(str(attempt["recognised_set"]), {"recognised": 0, "attempts": 0})["recognised"] += 1
    return counts


__all__ = ["mesh_offset", "photo_errors", "recognitions"]
