"""The Zenoh side of the payload streams, shared by the driver (`auv run`) and the publisher (`auv sim serve`):
key expressions, and peer sessions on explicit endpoints (no router, no multicast scouting).

Key expressions under a vehicle's prefix (e.g. `auv/sim`), each carrying one CDR-encoded ROS 2 message
(`mission.sensors.ros_msgs`):

| key | message |
|---|---|
| `PREFIX/mbes/points` | sensor_msgs/PointCloud2 (one ray per beam) |
| `PREFIX/scanner/points` | sensor_msgs/PointCloud2 (one ray per scanner ray, body frame) |
| `PREFIX/stereo/left/image_raw`, `PREFIX/stereo/right/image_raw` | sensor_msgs/Image (mono8) |
| `PREFIX/stereo/left/camera_info`, `PREFIX/stereo/right/camera_info` | sensor_msgs/CameraInfo |
| `PREFIX/SENSOR/request` | JSON `{"on": bool, "rate_hz": float or null}`: what the executive wants |
"""

from __future__ import annotations

from typing import Any

from mission.sensors import SensorError

MBES_POINTS = "mbes/points"
SCANNER_POINTS = "scanner/points"
STEREO_PARTS = ("left/image_raw", "right/image_raw", "left/camera_info", "right/camera_info")


def sensor_keys(prefix: str, sensor: str) -> list[str]:
    """The data keys of one sensor under `prefix`.

    >>> sensor_keys("auv/sim", "mbes")
    ['auv/sim/mbes/points']
    """
    if sensor == "stereo":
        return [f"{prefix}/stereo/{part}" for part in STEREO_PARTS]
    return [f"{prefix}/{sensor}/points"]


def request_key(prefix: str, sensor: str) -> str:
    return f"{prefix}/{sensor}/request"


def open_session(listen: list[str] | None = None, connect: list[str] | None = None) -> Any:
    """A Zenoh peer session listening on and/or connecting to explicit endpoints (`tcp/127.0.0.1:7447`)."""
    try:
        import zenoh
    except ImportError as exc:
        raise SensorError("the Zenoh transport needs eclipse-zenoh: pip install 'auv-mission[streams]'") from exc
    import json

    conf = zenoh.Config()
    conf.insert_json5("mode", '"peer"')
    conf.insert_json5("scouting/multicast/enabled", "false")
    if listen:
        conf.insert_json5("listen/endpoints", json.dumps(listen))
    if connect:
        conf.insert_json5("connect/endpoints", json.dumps(connect))
    try:
        return zenoh.open(conf)
    except Exception as exc:  # zenoh.ZError: a taken port, a malformed endpoint
        raise SensorError(f"cannot open a Zenoh session (listen {listen}, connect {connect}): {exc}") from exc
