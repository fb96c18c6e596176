"""Stereo perception: camera model and rectification, features, epipolar matching, ray triangulation.

Pure numpy + OpenCV: no simulator, no `mission` internals (seed 002 §3.1; seed 000 §3.1–3.2). The entry point is
`stereo_cloud(left, right, calib, detector="sift")`, which turns a stereo pair into a `Cloud` in the left camera
frame (OpenCV axes) with a depth uncertainty per point. SURF, which the seeds use, is patented and absent from the
OpenCV wheels: SIFT, ORB and Harris stand in (see `features`).
"""

from perception_plugins.stereo.camera import (
    Rectification,
    RectifiedStereo,
    StereoCalibration,
    backproject,
    project,
)
from perception_plugins.stereo.features import DETECTORS, Detector, Features, detect
from perception_plugins.stereo.matching import StereoMatches, epipolar_inliers, match_stereo, refine_disparities
from perception_plugins.stereo.pipeline import stereo_cloud
from perception_plugins.stereo.triangulation import Cloud, depth_sigma, triangulate

__all__ = ["DETECTORS", "Cloud", "Detector", "Features", "Rectification", "RectifiedStereo", "StereoCalibration",
           "StereoMatches", "backproject", "depth_sigma", "detect", "epipolar_inliers", "match_stereo", "project",
           "refine_disparities", "stereo_cloud", "triangulate"]
