"""ROS 2 message definitions (the `.msg` text with its dependencies, as `ros2 bag` stores it in an MCAP schema) of
the few message types `mission.mcap_log` writes, so that the log is written and read without ROS installed."""

from __future__ import annotations

_SEP = "=" * 80
_DEFS = {
    "builtin_interfaces/Time": "int32 sec\nuint32 nanosec",
    "std_msgs/Header": "builtin_interfaces/Time stamp\nstring frame_id",
    "geometry_msgs/Point": "float64 x\nfloat64 y\nfloat64 z",
    "geometry_msgs/Vector3": "float64 x\nfloat64 y\nfloat64 z",
    "geometry_msgs/Quaternion": "float64 x\nfloat64 y\nfloat64 z\nfloat64 w",
    "geometry_msgs/Pose": "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation",
    "geometry_msgs/PoseStamped": "std_msgs/Header header\ngeometry_msgs/Pose pose",
    "geometry_msgs/PoseWithCovariance": "geometry_msgs/Pose pose\nfloat64[36] covariance",
    "geometry_msgs/Twist": "geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular",
    "geometry_msgs/TwistWithCovariance": "geometry_msgs/Twist twist\nfloat64[36] covariance",
    "nav_msgs/Odometry": "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\n"
                         "geometry_msgs/TwistWithCovariance twist",
    "nav_msgs/Path": "std_msgs/Header header\ngeometry_msgs/PoseStamped[] poses",
    "sensor_msgs/PointField": "uint8 INT8=1\nuint8 UINT8=2\nuint8 INT16=3\nuint8 UINT16=4\nuint8 INT32=5\n"
                              "uint8 UINT32=6\nuint8 FLOAT32=7\nuint8 FLOAT64=8\nstring name\nuint32 offset\n"
                              "uint8 datatype\nuint32 count",
    "sensor_msgs/PointCloud2": "std_msgs/Header header\nuint32 height\nuint32 width\n"
                               "sensor_msgs/PointField[] fields\nbool is_bigendian\nuint32 point_step\n"
                               "uint32 row_step\nuint8[] data\nbool is_dense",
    "sensor_msgs/Image": "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\n"
                         "uint8 is_bigendian\nuint32 step\nuint8[] data",
    "sensor_msgs/NavSatStatus": "int8 STATUS_NO_FIX=-1\nint8 STATUS_FIX=0\nint8 status\nuint16 SERVICE_GPS=1\n"
                                "uint16 service",
    "sensor_msgs/NavSatFix": "std_msgs/Header header\nsensor_msgs/NavSatStatus status\nfloat64 latitude\n"
                             "float64 longitude\nfloat64 altitude\nfloat64[9] position_covariance\n"
                             "uint8 COVARIANCE_TYPE_UNKNOWN=0\nuint8 COVARIANCE_TYPE_APPROXIMATED=1\n"
                             "uint8 position_covariance_type",
    "rcl_interfaces/Log": "uint8 DEBUG=10\nuint8 INFO=20\nuint8 WARN=30\nuint8 ERROR=40\nuint8 FATAL=50\n"
                          "builtin_interfaces/Time stamp\nuint8 level\nstring name\nstring msg\nstring file\n"
                          "string function\nuint32 line",
}


def _deps(name: str, seen: list[str]) -> None:
    for line in _DEFS[name].splitlines():
        field_type = line.split()[0].split("[")[0]
        if "/" in field_type and field_type not in seen:
            seen.append(field_type)
            _deps(field_type, seen)


def msgdef(name: str) -> str:
    """The full definition of `name` ('pkg/Type'): its own fields, then each dependency once under `MSG: pkg/Type`.

    >>> text = msgdef("geometry_msgs/Pose")
    >>> text.splitlines()[0], text.count("MSG: ")
    ('geometry_msgs/Point position', 2)
    """
    seen: list[str] = []
    _deps(name, seen)
    return "\n".join([_DEFS[name], *(f"{_SEP}\nMSG: {dep}\n{_DEFS[dep]}" for dep in seen)]) + "\n"
