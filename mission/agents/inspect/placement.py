"""Where the inspect agent believes the object is: T_world_object in the navigation frame, first from the
database (or a survey's detection), then from referencing fixes, re-anchored by odometry in between."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from mission.frames import camera_pose
from mission.geometry import invert
from mission.language.mount import DOWN_DEG, mount_rotation
from mission.vehicle import NavState


@dataclass
class Placement:
    """The object's estimated pose and how far it is to be trusted.

    `T_wo` is the working estimate (a search hit may move it before it is confirmed); `trusted` is the database
    pose or the last fused fix, what an unconfirmed hit falls back to; `fixed` once views have been fused;
    `path_since_fix` is the odometry path since that fix, which the fix gate allows for; `tilt_deg` is the
    camera's mount (`sensors.stereo.mount`, `mission.language.mount`)."""

    T_wo: np.ndarray
    baseline: float = 0.0
    tilt_deg: float = DOWN_DEG
    trusted: np.ndarray = field(init=False)
    fixed: bool = False
    path_since_fix: float = 0.0

    def __post_init__(self) -> None:
        self.trusted = self.T_wo.copy()

    def heading(self) -> float:
        """The object's x-axis as a heading (degrees clockwise from north)."""
        x_axis = self.T_wo[:3, 0]
        return math.degrees(math.atan2(x_axis[1], x_axis[0])) % 360.0

    def fix(self, T_wo: np.ndarray) -> None:
        """Fused views place the object: trust it from now on."""
        self.T_wo = T_wo
        self.fixed = True
        self.path_since_fix = 0.0
        self.trusted = T_wo.copy()

    def fall_back(self) -> None:
        """Drop what an unconfirmed search hit suggested."""
        self.T_wo = self.trusted.copy()

    def camera_in_world(self, nav: NavState) -> np.ndarray:
        """T_world_cam of the left camera at the estimated pose `nav`."""
        return camera_pose(nav.north, nav.east, nav.depth, nav.heading, baseline=self.baseline,
                           R_body_cam=mount_rotation(self.tilt_deg))

    def camera_in_object(self, nav: NavState) -> np.ndarray:
        """T_object_cam at the estimated pose `nav`, in the object as placed now."""
        return np.asarray(invert(self.T_wo) @ self.camera_in_world(nav))
