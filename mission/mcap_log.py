"""A finished run folder as an MCAP log of ROS 2 messages (CDR), so that Foxglove (or `ros2 bag`) opens a run with
no viewer of our own. The layout `docs/foxglove_layout.json` arranges the topics.

Frames: the run's local NED world becomes ROS's ENU `map` frame (x = east, y = north, z = up = −depth), and the
vehicle's FRD body becomes `base_link` (FLU): a heading ψ (degrees clockwise from north) is the yaw
(90° − ψ) counter-clockwise from east. Times are the run's seconds from its start.

Topics:
- `/odometry/true`, `/odometry/estimated` (nav_msgs/Odometry): a message per trajectory row (the true one only
  where the row has the truth); the estimate carries the navigation's position sigma in its covariance;
- `/fix/estimated` (sensor_msgs/NavSatFix): the estimated track on the globe, when the mission has an `origin`;
- `/planned_path` (nav_msgs/Path): the plannable elements' paths (`mission.export.plan`) at the run's start;
- `/map/seabed` (sensor_msgs/PointCloud2): each survey's bathymetric grid from its multibeam soundings (x, y, z
  and the information map as `intensity`), and `/map/occupied`: the occupied voxels each explore element mapped;
  a message per element, at the time it ended (the run folder keeps these grids, not the raw pings);
- `/stereo/left`, `/stereo/right` (sensor_msgs/Image, mono8): the stereo pairs of `stereo/`, when recorded;
- `/rosout` (rcl_interfaces/Log): every event of `events.jsonl`, safety events at ERROR and failures at WARN.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from mission.errors import AuvError
from mission.export.plan import plan_legs
from mission.ros2_msgdefs import msgdef
from mission.runfolder import RunData, read_run_folder

FRAME_WORLD = "map"
FRAME_BODY = "base_link"
ERROR_EVENTS = ("safety_violation", "abort", "link_lost", "stopped")
WARN_EVENTS = ("element_failed", "agent_fault", "plugin_fault", "object_not_found", "set_not_recognised")
TYPES = ("nav_msgs/Odometry", "nav_msgs/Path", "sensor_msgs/PointCloud2", "sensor_msgs/Image",
         "sensor_msgs/NavSatFix", "rcl_interfaces/Log")
FLOAT32 = 7


def _stamp(t: float) -> dict[str, int]:
    ns = _ns(t)
    return {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}


def _ns(t: float) -> int:
    return max(0, round(t * 1e9))


def _header(t: float, frame: str = FRAME_WORLD) -> dict[str, Any]:
    return {"stamp": _stamp(t), "frame_id": frame}


def enu_pose(north: float, east: float, depth: float, heading_deg: float) -> dict[str, Any]:
    """A geometry_msgs/Pose in the ENU `map` frame of a NED position and a heading (degrees from north).

    >>> p = enu_pose(10.0, 2.0, 5.0, 90.0)   # heading east: no yaw in ENU
    >>> p["position"], round(p["orientation"]["z"], 9), p["orientation"]["w"]
    ({'x': 2.0, 'y': 10.0, 'z': -5.0}, 0.0, 1.0)
    """
    yaw = math.radians(90.0 - heading_deg) if math.isfinite(heading_deg) else 0.0
    return {"position": {"x": float(east), "y": float(north), "z": -float(depth)},
            "orientation": {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2.0), "w": math.cos(yaw / 2.0)}}


def _odometry(t: float, pose: dict[str, Any], speed: float, sigma: float) -> dict[str, Any]:
    cov = [0.0] * 36
    if math.isfinite(sigma):
        cov[0] = cov[7] = sigma * sigma
    return {"header": _header(t), "child_frame_id": FRAME_BODY,
            "pose": {"pose": pose, "covariance": cov},
            "twist": {"twist": {"linear": {"x": speed if math.isfinite(speed) else 0.0, "y": 0.0, "z": 0.0},
                                "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}, "covariance": [0.0] * 36}}


def point_cloud(t: float, xyz_enu: np.ndarray, intensity: np.ndarray | None = None) -> dict[str, Any]:
    """A sensor_msgs/PointCloud2 of float32 x, y, z (and intensity) points in the `map` frame."""
    cols = [np.asarray(xyz_enu, np.float32).reshape(-1, 3)]
    names = ["x", "y", "z"]
    if intensity is not None:
        cols.append(np.asarray(intensity, np.float32).reshape(-1, 1))
        names.append("intensity")
    data = np.ascontiguousarray(np.hstack(cols), dtype="<f4")
    fields = [{"name": n, "offset": 4 * k, "datatype": FLOAT32, "count": 1} for k, n in enumerate(names)]
    return {"header": _header(t), "height": 1, "width": len(data), "fields": fields, "is_bigendian": False,
            "point_step": 4 * len(names), "row_step": 4 * len(names) * len(data), "data": data.tobytes(),
            "is_dense": True}


class _Log:
    """The MCAP writer with one schema per message type, counting what it writes."""

    def __init__(self, out: Path):
        try:
            from mcap_ros2.writer import Writer
        except ImportError as exc:
            raise AuvError("MCAP logs need mcap and mcap-ros2-support: pip install 'auv-mission[interop]'") from exc
        self._file = out.open("wb")
        self.writer = Writer(self._file)
        self.schemas = {name: self.writer.register_msgdef(name, msgdef(name)) for name in TYPES}
        self.count = 0

    def write(self, topic: str, msg_type: str, message: dict[str, Any], t: float) -> None:
        self.writer.write_message(topic, self.schemas[msg_type], message, log_time=_ns(t), sequence=self.count)
        self.count += 1

    def close(self) -> None:
        self.writer.finish()  # type: ignore[no-untyped-call]
        self._file.close()


def _odometry_topics(log: _Log, run: RunData) -> None:
    tr = run.trajectory
    for i, t in enumerate(tr["time"]):
        t = float(t)
        speed = float(tr["speed"][i])
        if math.isfinite(tr["north"][i]):
            log.write("/odometry/true", "nav_msgs/Odometry", _odometry(
                t, enu_pose(tr["north"][i], tr["east"][i], tr["depth"][i], tr["heading"][i]), speed, math.nan), t)
        log.write("/odometry/estimated", "nav_msgs/Odometry", _odometry(
            t, enu_pose(tr["north_est"][i], tr["east_est"][i], tr["depth_est"][i], tr["heading_est"][i]), speed,
            float(tr["position_sigma"][i])), t)
    if run.mission.origin is None:
        return
    from mission.geodesy import ned_to_geodetic

    lat, lon = ned_to_geodetic(tr["north_est"], tr["east_est"], run.mission.origin.lat, run.mission.origin.lon)
    for i, t in enumerate(tr["time"]):
        sigma2 = float(tr["position_sigma"][i]) ** 2 if math.isfinite(tr["position_sigma"][i]) else 0.0
        log.write("/fix/estimated", "sensor_msgs/NavSatFix", {
            "header": _header(float(t), FRAME_BODY), "status": {"status": 0, "service": 0},
            "latitude": float(lat[i]), "longitude": float(lon[i]), "altitude": -float(tr["depth_est"][i]),
            "position_covariance": [sigma2, 0.0, 0.0, 0.0, sigma2, 0.0, 0.0, 0.0, 0.0],
            "position_covariance_type": 1}, float(t))


def _planned_path(log: _Log, run: RunData, t0: float) -> None:
    poses = []
    for leg in plan_legs(run.mission, strict=False):
        depth = leg.depth if leg.depth is not None else math.nan
        for n, e in leg.points_ne:
            pose = enu_pose(n, e, depth if math.isfinite(depth) else 0.0, math.nan)
            poses.append({"header": _header(t0), "pose": pose})
    log.write("/planned_path", "nav_msgs/Path", {"header": _header(t0), "poses": poses}, t0)


def _element_end(run: RunData, element: str) -> float:
    times = [float(e.get("time", 0.0)) for e in run.events if e.get("element") == element]
    return max(times) if times else float(run.trajectory["time"][-1])


def _maps(log: _Log, run: RunData) -> None:
    for element, m in sorted(run.maps.items()):
        t = _element_end(run, element)
        if {"depth", "north0", "east0", "cell"} <= set(m):
            depth = np.asarray(m["depth"], float)
            rows, cols = np.nonzero(np.isfinite(depth))
            cell = float(m["cell"])
            north = float(m["north0"]) + rows * cell
            east = float(m["east0"]) + cols * cell
            info = np.asarray(m["info"], float)[rows, cols] if "info" in m else None
            xyz = np.column_stack([east, north, -depth[rows, cols]])
            log.write("/map/seabed", "sensor_msgs/PointCloud2", point_cloud(t, xyz, info), t)
        if "explore_occupied" in m:
            occ = np.asarray(m["explore_occupied"], float).reshape(-1, 4)
            xyz = np.column_stack([occ[:, 1], occ[:, 0], -occ[:, 2]])
            log.write("/map/occupied", "sensor_msgs/PointCloud2", point_cloud(t, xyz), t)


def _events(log: _Log, run: RunData) -> None:
    for ev in run.events:
        name = str(ev.get("event", "event"))
        level = 40 if name in ERROR_EVENTS else 30 if name in WARN_EVENTS else 20
        fields = {k: v for k, v in ev.items() if k not in ("time", "event")}
        t = float(ev.get("time", 0.0))
        log.write("/rosout", "rcl_interfaces/Log", {
            "stamp": _stamp(t), "level": level, "name": "auv.executive",
            "msg": f"{name} {json.dumps(fields, sort_keys=True)}", "file": "events.jsonl", "function": name,
            "line": 0}, t)


def _stereo(log: _Log, folder: Path) -> None:
    times_file = folder / "times.txt"
    if not times_file.is_file():
        return
    import cv2

    times = np.atleast_1d(np.loadtxt(times_file, ndmin=1))
    for side, topic in (("image_0", "/stereo/left"), ("image_1", "/stereo/right")):
        files = sorted((folder / side).glob("*.png"))
        for t, path in zip(times, files, strict=False):
            img = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
            if img is None:
                raise AuvError(f"{path}: not an image")
            log.write(topic, "sensor_msgs/Image", {
                "header": _header(float(t), "camera_left" if side == "image_0" else "camera_right"),
                "height": img.shape[0], "width": img.shape[1], "encoding": "mono8", "is_bigendian": 0,
                "step": img.shape[1], "data": np.ascontiguousarray(img).tobytes()}, float(t))


def write_mcap(run_dir: str | Path, out: str | Path | None = None) -> int:
    """Write the run folder `run_dir` as an MCAP log (default `RUN_DIR/run.mcap`); the number of messages.

    Raises RunFolderError when `run_dir` is not a run folder, AuvError when the MCAP libraries are missing.
    """
    run = read_run_folder(run_dir)
    target = Path(out) if out is not None else run.folder / "run.mcap"
    log = _Log(target)
    try:
        log.writer.add_metadata("auv-mission", {
            "mission": run.mission.name, "world_frame": "map: ENU (x east, y north, z up) from the run's NED",
            "body_frame": "base_link: FLU; yaw = 90 deg - heading",
            "origin": json.dumps(run.mission.origin.model_dump() if run.mission.origin else None)})
        t0 = float(run.trajectory["time"][0]) if len(run.trajectory["time"]) else 0.0
        _planned_path(log, run, t0)
        _odometry_topics(log, run)
        _maps(log, run)
        _events(log, run)
        _stereo(log, run.folder / "stereo")
    finally:
        log.close()
    return log.count
