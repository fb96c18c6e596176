"""Frames and transforms: local NED world, object frames, 4×4 homogeneous matrices `T_a_b` (b → a).

Headings are degrees clockwise from north (a rotation about the world z-axis, which points down).

>>> import numpy as np
>>> T_world_object = pose_matrix(10.0, 20.0, 50.0, heading_deg=90.0)
>>> transform_points(T_world_object, np.array([[1.0, 0.0, 0.0]])).round(6).tolist()
[[10.0, 21.0, 50.0]]
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from mission.geometry import invert as invert
from mission.geometry import transform_points as transform_points

Array = NDArray[np.float64]


def rotation_zyx(heading_deg: float, pitch_deg: float = 0.0, roll_deg: float = 0.0) -> Array:
    """R = Rz(heading)·Ry(pitch)·Rx(roll): body/object axes expressed in the NED world."""
    cz, sz = math.cos(math.radians(heading_deg)), math.sin(math.radians(heading_deg))
    cy, sy = math.cos(math.radians(pitch_deg)), math.sin(math.radians(pitch_deg))
    cx, sx = math.cos(math.radians(roll_deg)), math.sin(math.radians(roll_deg))
    rz = np.array([[cz, -sz, 0.0], [sz, cz, 0.0], [0.0, 0.0, 1.0]])
    ry = np.array([[cy, 0.0, sy], [0.0, 1.0, 0.0], [-sy, 0.0, cy]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cx, -sx], [0.0, sx, cx]])
    return np.asarray(rz @ ry @ rx, dtype=float)


def pose_matrix(
    north: float, east: float, depth: float, heading_deg: float = 0.0, pitch_deg: float = 0.0, roll_deg: float = 0.0
) -> Array:
    """T_world_frame for a frame at (north, east, depth) with the given heading, pitch and roll."""
    T = np.eye(4)
    T[:3, :3] = rotation_zyx(heading_deg, pitch_deg, roll_deg)
    T[:3, 3] = (north, east, depth)
    return T




def heading_of(T_world_frame: Array) -> float:
    """Heading (deg, clockwise from north, in [0, 360)) of a frame's x-axis projected on the horizontal."""
    x_axis = T_world_frame[:3, 0]
    return math.degrees(math.atan2(x_axis[1], x_axis[0])) % 360.0


def wrap_deg(angle: float) -> float:
    """Angle wrapped to (-180, 180].

    >>> wrap_deg(190.0), wrap_deg(-180.0)
    (-170.0, 180.0)
    """
    a = math.fmod(angle + 180.0, 360.0)
    if a <= 0.0:
        a += 360.0
    return a - 180.0


# The down-looking camera: optical axis along body z (down), image x to starboard, image y aft (OpenCV camera
# axes; right-handed since starboard × aft = down). The left camera sits baseline/2 to port of the body origin,
# the right one baseline/2 to starboard.
R_BODY_CAM = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


def camera_pose(north: float, east: float, depth: float, heading_deg: float, pitch_deg: float = 0.0,
                roll_deg: float = 0.0, baseline: float = 0.0, R_body_cam: Array = R_BODY_CAM) -> Array:
    """T_world_cam of the left camera on a vehicle at this pose, mounted as `R_body_cam` says (default: looking
    down; `mission.language.mount.Mount.R_body_cam` gives a tilted mount's).

    >>> T = camera_pose(0.0, 0.0, 10.0, 90.0, baseline=0.5)  # heading east: image x (starboard) points south
    >>> T[:3, 0].round(6).tolist(), T[:3, 2].round(6).tolist(), (T[:3, 3].round(6) + 0.0).tolist()
    ([-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.25, 0.0, 10.0])
    """
    T_world_body = pose_matrix(north, east, depth, heading_deg, pitch_deg, roll_deg)
    T_body_cam = np.eye(4)
    T_body_cam[:3, :3] = R_body_cam
    T_body_cam[:3, 3] = (0.0, -baseline / 2.0, 0.0)
    return T_world_body @ T_body_cam
