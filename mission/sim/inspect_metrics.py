"""Scoring an `inspect` element against the truth: where the camera really was at each photograph, whether the
target is really in the picture, and how far visual odometry drifted between referencing fixes."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from mission.frames import invert, transform_points
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


def inspect_truth(item: dict[str, Any], vehicle: SimulatedVehicle, scene: Scene) -> None:
    """Add truth-based figures to an inspect element's metrics (in place)."""
    mission = vehicle.mission
    truth = next((o for o in scene.objects if o.database == item.get("object")), None)
    stereo = mission.sensors.stereo
    vo = item.get("vo", {})
    track = vo.pop("track", [])
    if truth is None or stereo is None:
        return
    obj = mission.object(item["object"])
    at = {t.id: np.asarray(t.at, dtype=float) for t in obj.targets}
    K = intrinsics(stereo)
    frames = dict(vehicle.log.frames)
    T_object_world = invert(truth.T_world_object)
    per_target: dict[str, dict[str, Any]] = item.get("targets", {})
    for photo in item.get("photos", []):
        T_world_cam = _frame_pose(frames, photo["time"])
        if T_world_cam is None:
            continue
        T_object_cam = T_object_world @ T_world_cam
        viewpoint = np.asarray(photo["viewpoint_object"], dtype=float)
        target_world = transform_points(truth.T_world_object, at[photo["target"]][None, :])[0]
        p_cam = transform_points(invert(T_world_cam), target_world[None, :])[0]
        axis = T_world_cam[:3, 2]
        direction = (target_world - T_world_cam[:3, 3]) / np.linalg.norm(target_world - T_world_cam[:3, 3])
        u = K[0, 0] * p_cam[0] / p_cam[2] + K[0, 2] if p_cam[2] > 0 else math.nan
        v = K[1, 1] * p_cam[1] / p_cam[2] + K[1, 2] if p_cam[2] > 0 else math.nan
        est = np.asarray(photo.pop("T_object_cam_est"), dtype=float)
        photo["camera_error_m"] = round(float(np.linalg.norm(T_object_cam[:3, 3] - viewpoint)), 4)
        photo["pointing_error_deg"] = round(math.degrees(math.acos(float(np.clip(axis @ direction, -1, 1)))), 3)
        photo["target_pixel"] = [round(u, 1), round(v, 1)]
        photo["target_in_image"] = bool(0 <= u < stereo.width and 0 <= v < stereo.height)
        photo["pose_estimate_error_m"] = round(float(np.linalg.norm(est[:3, 3] - T_object_cam[:3, 3])), 4)
    for tid, entry in per_target.items():
        shots = [p for p in item.get("photos", []) if p["target"] == tid and "camera_error_m" in p]
        entry["camera_error_max_m"] = max((p["camera_error_m"] for p in shots), default=None)
        entry["pointing_error_max_deg"] = max((p["pointing_error_deg"] for p in shots), default=None)
        entry["target_in_every_photo"] = bool(shots) and all(p["target_in_image"] for p in shots)
        entry["ok"] = bool(entry["photos"] >= entry["photos_requested"] and entry["target_in_every_photo"]
                           and entry["camera_error_max_m"] is not None
                           and entry["camera_error_max_m"] <= CAMERA_TOLERANCE_M)
    item["targets_ok"] = sum(1 for e in per_target.values() if e.get("ok"))
    errors = []
    for t, x, y, z in track:
        T_world_cam = _frame_pose(frames, t)
        if T_world_cam is not None:
            errors.append(float(np.linalg.norm((T_object_world @ T_world_cam)[:3, 3] - np.array([x, y, z]))))
    if errors:
        vo["camera_error_rms_m"] = round(float(np.sqrt(np.mean(np.square(errors)))), 4)
        vo["camera_error_max_m"] = round(max(errors), 4)
    vo["track_frames"] = len(track)
