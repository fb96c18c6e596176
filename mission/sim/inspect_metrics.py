"""Scoring an `inspect` element against the truth: where the camera really was at each photograph (against the
feasible viewpoint the agent planned, `camera_error_m`, and against the designed one, `designed_error_m`), whether
the target is really in the picture (its true position projected through the camera as mounted), and how far
visual odometry drifted between referencing fixes."""

from __future__ import annotations

import copy
import math
from typing import Any

import numpy as np

from mission.agents.report import InspectReport, Photo
from mission.frames import invert, transform_points
from mission.language.models import Stereo
from mission.sim.camera import intrinsics
from mission.sim.vehicle import SimulatedVehicle
from mission.world.scene import Scene

CAMERA_TOLERANCE_M = 0.1  # the bar: the camera within this of its planned viewpoint


def _frame_pose(frames: dict[float, Any], t: float) -> np.ndarray | None:
    pose = frames.get(t)
    if pose is None and frames:  # times are copied through JSON-friendly rounding in places
        nearest = min(frames, key=lambda k: abs(k - t))
        pose = frames[nearest] if abs(nearest - t) < 1e-3 else None
    return None if pose is None else np.asarray(pose, dtype=float)


def _photo_truth(photo: Photo, T_world_cam: np.ndarray, T_world_object: np.ndarray, target_object: np.ndarray,
                 stereo: Stereo) -> dict[str, Any]:
    """A photograph's true camera error, pointing error, the target's pixel and whether it is in the image."""
    K = intrinsics(stereo)
    T_object_cam = invert(T_world_object) @ T_world_cam
    target_world = transform_points(T_world_object, target_object[None, :])[0]
    p_cam = transform_points(invert(T_world_cam), target_world[None, :])[0]
    axis = T_world_cam[:3, 2]
    direction = (target_world - T_world_cam[:3, 3]) / np.linalg.norm(target_world - T_world_cam[:3, 3])
    u = K[0, 0] * p_cam[0] / p_cam[2] + K[0, 2] if p_cam[2] > 0 else math.nan
    v = K[1, 1] * p_cam[1] / p_cam[2] + K[1, 2] if p_cam[2] > 0 else math.nan
    est = np.asarray(photo.T_object_cam_est, dtype=float)
    viewpoint = np.asarray(photo.viewpoint_object, dtype=float)
    designed = np.asarray(photo.designed_object if photo.designed_object is not None else viewpoint, dtype=float)
    return {"camera_error_m": round(float(np.linalg.norm(T_object_cam[:3, 3] - viewpoint)), 4),
            "designed_error_m": round(float(np.linalg.norm(T_object_cam[:3, 3] - designed)), 4),
            "pointing_error_deg": round(math.degrees(math.acos(float(np.clip(axis @ direction, -1, 1)))), 3),
            "target_pixel": [round(u, 1), round(v, 1)],
            "target_in_image": bool(0 <= u < stereo.width and 0 <= v < stereo.height),
            "pose_estimate_error_m": round(float(np.linalg.norm(est[:3, 3] - T_object_cam[:3, 3])), 4)}


def inspect_truth(report: InspectReport, vehicle: SimulatedVehicle, scene: Scene) -> dict[str, Any]:
    """An inspect element's fields of `metrics.json`: the report's, with the truth-based figures added (the
    estimated camera poses and the odometry track give way to their errors)."""
    out = copy.deepcopy(report.as_json())
    vo = out["vo"]
    del vo["track"]
    mission = vehicle.mission
    truth = next((o for o in scene.objects if o.database == report.object), None)
    stereo = mission.sensors.stereo
    if truth is None or stereo is None:
        return out
    at = {t.id: np.asarray(t.at, dtype=float) for t in mission.object(report.object).targets}
    frames = dict(vehicle.log.frames)
    for photo, entry in zip(report.photos, out["photos"], strict=True):
        T_world_cam = _frame_pose(frames, photo.time)
        if T_world_cam is None:
            continue
        del entry["T_object_cam_est"]
        entry.update(_photo_truth(photo, T_world_cam, truth.T_world_object, at[photo.target], stereo))
    for tid, outcome in report.targets.items():
        entry = out["targets"][tid]
        shots = [e for p, e in zip(report.photos, out["photos"], strict=True) if p.target == tid
                 and "camera_error_m" in e]
        entry["camera_error_max_m"] = max((e["camera_error_m"] for e in shots), default=None)
        entry["designed_error_max_m"] = max((e["designed_error_m"] for e in shots), default=None)
        entry["pointing_error_max_deg"] = max((e["pointing_error_deg"] for e in shots), default=None)
        entry["target_in_every_photo"] = bool(shots) and all(e["target_in_image"] for e in shots)
        entry["ok"] = bool(outcome.done and entry["target_in_every_photo"] and entry["camera_error_max_m"] is not None
                           and entry["camera_error_max_m"] <= CAMERA_TOLERANCE_M)
    out["targets_ok"] = sum(1 for e in out["targets"].values() if e["ok"])
    T_object_world = invert(truth.T_world_object)
    errors = []
    for t, x, y, z in report.vo.track:
        T_world_cam = _frame_pose(frames, t)
        if T_world_cam is not None:
            errors.append(float(np.linalg.norm((T_object_world @ T_world_cam)[:3, 3] - np.array([x, y, z]))))
    if errors:
        vo["camera_error_rms_m"] = round(float(np.sqrt(np.mean(np.square(errors)))), 4)
        vo["camera_error_max_m"] = round(max(errors), 4)
    vo["track_frames"] = len(report.vo.track)
    return out
