"""Stereo visual odometry (seed 003): the classic two-position scheme, long KLT tracking over fragments, the
adaptive step, and the virtual reference network; the `stereo-vo` perception plug-in.

Public API: `read_kitti_sequence(path)` (sequences in the KITTI odometry layout), `read_calibration(path)`
(K and baseline of a KITTI `calib.txt`), `estimate_trajectory(frames,
method, progress, **options)` (T_world_cam of every frame), `METHODS`, `Odometer` / `OdometerSettings` (the
push-a-frame engine behind both), the adaptive-step formulas (`adaptive`), and `VoError` (a bad sequence or
option). Pure numpy + OpenCV; of `mission` only the plug-in contract is imported. Camera frames follow OpenCV
(x right, y down, z along the optical axis); `T_a_b` maps frame b into frame a.
"""

from perception_plugins.vo.adaptive import (
    common_view_mask,
    field_of_view_along,
    footprint,
    overlap_displacement,
    step_frames,
    step_time,
)
from perception_plugins.vo.errors import VoError
from perception_plugins.vo.kitti import KittiSequence, read_calibration, read_kitti_sequence
from perception_plugins.vo.network import NetworkSettings, ReferenceNetwork
from perception_plugins.vo.odometer import Estimate, Odometer, OdometerSettings
from perception_plugins.vo.trajectory import METHODS, estimate_trajectory, run_odometer, settings_for

__all__ = ["METHODS", "Estimate", "KittiSequence", "NetworkSettings", "Odometer", "OdometerSettings",
           "ReferenceNetwork", "VoError", "common_view_mask", "estimate_trajectory", "field_of_view_along",
           "footprint", "overlap_displacement", "read_calibration", "read_kitti_sequence", "run_odometer",
           "settings_for", "step_frames", "step_time"]
