"""ROS 2 message shapes of the payload streams, CDR-encoded (little endian, with the 4-byte encapsulation header,
as `rmw_zenoh` carries them) by `rosbags`' serde (pure Python, Apache-2.0):

- stereo: `sensor_msgs/msg/Image` (`mono8`) and `sensor_msgs/msg/CameraInfo` per camera; the rectified K in
  `k` and `p`, and on the right camera `p[3] = -fx·baseline` (the ROS stereo convention).
- multibeam and scanner: `sensor_msgs/msg/PointCloud2`, one point per beam or ray, in the sensor's frame
  (multibeam: x forward, y starboard, z down; scanner: the vehicle body frame, x forward, y starboard, z down).
  Fields `x`, `y`, `z` (FLOAT32, metres: the ray's direction times its range, the sensor's max range when there is
  no return) and `hit` (UINT8, 1 for a return); point step 16 bytes. A beam's across-track angle is
  atan2(y, z).

Stamps are the sensor's own time (the vehicle's clock) in `header.stamp`.
"""

from __future__ import annotations

import math
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mission.plugin_api import StereoImages
from mission.vehicle import ScanFrame, SonarPing

IMAGE, CAMERA_INFO, CLOUD = "sensor_msgs/msg/Image", "sensor_msgs/msg/CameraInfo", "sensor_msgs/msg/PointCloud2"
RAY_DTYPE = np.dtype({"names": ["x", "y", "z", "hit"], "formats": ["<f4", "<f4", "<f4", "u1"],
                      "offsets": [0, 4, 8, 12], "itemsize": 16})


@cache
def _store() -> Any:
    try:
        from rosbags.typesys import Stores, get_typestore
    except ImportError as exc:
        from mission.sensors import SensorError

        raise SensorError("ROS 2 message encoding needs rosbags: pip install 'auv-mission[streams]'") from exc
    return get_typestore(Stores.ROS2_HUMBLE)


def _header(t: float, frame_id: str) -> Any:
    ts = _store().types
    sec = math.floor(t)
    return ts["std_msgs/msg/Header"](ts["builtin_interfaces/msg/Time"](int(sec), int(round((t - sec) * 1e9))),
                                     frame_id)


def stamp_seconds(msg: Any) -> float:
    return float(msg.header.stamp.sec) + float(msg.header.stamp.nanosec) * 1e-9


def encode(msg: Any) -> bytes:
    return bytes(_store().serialize_cdr(msg, msg.__msgtype__))


def decode(data: bytes, typename: str) -> Any:
    return _store().deserialize_cdr(data, typename)


# -- stereo ------------------------------------------------------------------------------------------------------
def image_msg(t: float, image: NDArray[np.uint8], frame_id: str) -> Any:
    h, w = image.shape[:2]
    return _store().types[IMAGE](_header(t, frame_id), h, w, "mono8", 0, w, np.ascontiguousarray(image).reshape(-1))


def image_from_msg(msg: Any) -> NDArray[np.uint8]:
    if msg.encoding != "mono8":
        raise ValueError(f"image encoding {msg.encoding!r}: expected mono8")
    data = np.asarray(msg.data, dtype=np.uint8)
    return data.reshape(msg.height, msg.step)[:, : msg.width].copy()


def camera_info_msg(t: float, K: NDArray[np.float64], width: int, height: int, baseline: float, frame_id: str,
                    right: bool) -> Any:
    ts = _store().types
    k = np.asarray(K, dtype=np.float64)
    p = np.zeros((3, 4))
    p[:, :3] = k
    if right:
        p[0, 3] = -k[0, 0] * baseline
    roi = ts["sensor_msgs/msg/RegionOfInterest"](0, 0, 0, 0, False)
    return ts[CAMERA_INFO](_header(t, frame_id), height, width, "plumb_bob", np.zeros(5), k.reshape(-1),
                           np.eye(3).reshape(-1), p.reshape(-1), 0, 0, roi)


def stereo_from_msgs(left: Any, right: Any, left_info: Any, right_info: Any) -> StereoImages:
    """The pair as the agents take it: K from the left camera's info, the baseline from the right's P."""
    K = np.asarray(left_info.k, dtype=np.float64).reshape(3, 3)
    p = np.asarray(right_info.p, dtype=np.float64).reshape(3, 4)
    return StereoImages(stamp_seconds(left), image_from_msg(left), image_from_msg(right), K, -p[0, 3] / p[0, 0])


# -- multibeam and scanner -------------------------------------------------------------------------------------
def ray_cloud_msg(t: float, directions: NDArray[np.float64], ranges: NDArray[np.float64], hit: NDArray[np.bool_],
                  frame_id: str) -> Any:
    ts = _store().types
    rays = np.zeros(len(ranges), dtype=RAY_DTYPE)
    points = np.asarray(directions, dtype=np.float64) * np.asarray(ranges, dtype=np.float64)[:, None]
    rays["x"], rays["y"], rays["z"], rays["hit"] = points[:, 0], points[:, 1], points[:, 2], hit
    pf = ts["sensor_msgs/msg/PointField"]
    fields = [pf("x", 0, pf.FLOAT32, 1), pf("y", 4, pf.FLOAT32, 1), pf("z", 8, pf.FLOAT32, 1),
              pf("hit", 12, pf.UINT8, 1)]
    n = len(rays)
    return ts[CLOUD](_header(t, frame_id), 1, n, fields, False, RAY_DTYPE.itemsize, RAY_DTYPE.itemsize * n,
                     rays.view(np.uint8).reshape(-1), True)


def rays_from_msg(msg: Any) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
    """(unit directions (N, 3), ranges (N,), hit (N,)) of a ray cloud."""
    names = [f.name for f in msg.fields]
    if names[:4] != ["x", "y", "z", "hit"] or msg.point_step != RAY_DTYPE.itemsize:
        raise ValueError(f"point cloud fields {names} (step {msg.point_step}): expected x, y, z, hit (step 16)")
    rays = np.frombuffer(np.asarray(msg.data, dtype=np.uint8).tobytes(), dtype=RAY_DTYPE)
    points = np.stack([rays["x"], rays["y"], rays["z"]], axis=1).astype(np.float64)
    ranges = np.linalg.norm(points, axis=1)
    directions = points / np.maximum(ranges, 1e-12)[:, None]
    return directions, ranges, rays["hit"].astype(bool)


def mbes_directions(angles_deg: NDArray[np.float64]) -> NDArray[np.float64]:
    """Beam directions in the sonar frame (x forward, y starboard, z down) from across-track angles."""
    a = np.radians(np.asarray(angles_deg, dtype=np.float64))
    return np.stack([np.zeros_like(a), np.sin(a), np.cos(a)], axis=1)


def sonar_from_msg(msg: Any) -> SonarPing:
    directions, ranges, hit = rays_from_msg(msg)
    angles = np.degrees(np.arctan2(directions[:, 1], directions[:, 2]))
    nan = math.nan
    return SonarPing(stamp_seconds(msg), ranges, angles, hit, nan, nan, nan, nan, nan)


def scan_from_msg(msg: Any, max_range: float) -> ScanFrame:
    directions, ranges, hit = rays_from_msg(msg)
    nan = math.nan
    return ScanFrame(stamp_seconds(msg), ranges, directions, hit, max_range, nan, nan, nan, nan, nan)
