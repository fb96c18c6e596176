"""How the stereo camera is mounted on the vehicle (`sensors.stereo.mount`; seed 002 §2.2: side surfaces need
oriented cameras): a fixed tilt about the vehicle's starboard axis. The simulator renders through it, the agents
compute the camera's pose through it, the metrics score photos through it.

`tilt_deg` is the optical axis's pitch down from horizontal-forward: 90 (the default) looks straight down (optical
axis = body z, image x = body y, image y = −body x, `mission.frames.R_BODY_CAM`), 0 looks straight ahead (image y
down). In between, the camera looks forward and down; image x stays along body y (starboard).
"""

from __future__ import annotations

import math
from typing import Annotated

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from mission.frames import R_BODY_CAM, Array
from mission.language.streamed import Streamed

DOWN_DEG = 90.0  # the default mount: the camera looks straight down


class Mount(BaseModel):
    """A fixed camera mount: `tilt_deg` down from horizontal-forward (0–90; 90 = straight down)."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)  # as `models.Strict`

    tilt_deg: Annotated[float, Field(ge=0.0, le=90.0)] = DOWN_DEG

    @property
    def looks_down(self) -> bool:
        return self.tilt_deg == DOWN_DEG

    def R_body_cam(self) -> Array:
        """The camera's axes in the body frame (columns: image x, image y, optical axis).

        >>> Mount().R_body_cam().tolist() == R_BODY_CAM.tolist()
        True
        >>> (Mount(tilt_deg=0).R_body_cam().round(6) + 0.0).tolist()  # looking ahead: image y down, axis forward
        [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
        """
        return mount_rotation(self.tilt_deg)


def mount_rotation(tilt_deg: float) -> Array:
    """R_body_cam of a camera tilted `tilt_deg` down from horizontal-forward (exactly `R_BODY_CAM` at 90)."""
    if tilt_deg == DOWN_DEG:
        return R_BODY_CAM.copy()
    c, s = math.cos(math.radians(tilt_deg)), math.sin(math.radians(tilt_deg))
    # image x: starboard; optical axis: (cos, 0, sin) forward and down; image y = axis × x
    return np.array([[0.0, -s, c], [1.0, 0.0, 0.0], [0.0, c, s]])


class Mounted(Streamed):
    """A payload sensor entry with a fixed mount (`sensors.stereo`)."""

    mount: Mount = Mount()


def R_body_cam_of(sensor: Mounted | None) -> Array:
    """The mount's R_body_cam of a sensor entry; looking down when the mission has none."""
    return sensor.mount.R_body_cam() if sensor is not None else R_BODY_CAM.copy()


__all__ = ["DOWN_DEG", "Mount", "Mounted", "R_body_cam_of", "Streamed", "mount_rotation"]
