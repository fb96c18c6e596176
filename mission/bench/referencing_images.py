"""The "Images" part of `auv bench referencing` (issue 3): the reference world seen from 3.6 m above
manifold-1's roof top at 1200×900 (seed 000's virtual scene); the `stereo-referencing` plug-in on each rendered
pair, with the prior a search-stage referencing leaves (±10 cm, ±1°). Recognition rate, camera position error
in the object frame against the truth (mm), and plug-in time per stereo pair on one core.
"""

from __future__ import annotations

import os
import statistics
import time
from typing import Any

import numpy as np

from mission.bench import REPO
from mission.frames import heading_of, invert, pose_matrix, transform_points
from mission.plugin_api import PointSetModel, ReferencingRequest, StereoImages

MODULE_TOP = np.array([[2, 1, -2], [6, 1, -2], [6, 4, -2], [2, 4, -2], [4, 2.5, -2.6]], dtype=float)


def run_images(quick: bool) -> dict[str, Any]:
    os.environ.setdefault("MUJOCO_GL", "egl")
    import cv2

    from mission.language.loader import load_world
    from mission.language.models import Stereo
    from mission.sim.camera import StereoCamera
    from perception_plugins.referencing.plugin import StereoReferencingPlugin

    cv2.setNumThreads(1)
    world = load_world(REPO / "worlds" / "sps_field.yaml")
    camera = StereoCamera(world, Stereo(width=1200, height=900, fx=1000.0, baseline=0.25))
    manifold = next(o for o in camera.world.scene.objects if o.id == "manifold-1")
    plugin = StereoReferencingPlugin()
    plugin.configure({"sensors": {"stereo": {"max_range": 8.0}}})
    rng = np.random.default_rng(3)
    placed = transform_points(manifold.T_world_object, MODULE_TOP)
    roof = placed[:4].mean(axis=0)
    top = float(placed[:, 2].min())  # the lifting point on the roof: the camera is 3.6 m above it
    heading = heading_of(manifold.T_world_object) - 90.0
    recognised, errors_mm, times_ms = 0, [], []
    frames = 8 if quick else 30
    for _ in range(frames):
        dn, de = rng.uniform(-0.2, 0.2, 2)
        frame = camera.render_at(roof[0] + dn, roof[1] + de, top - 3.6, heading + rng.uniform(-2, 2))
        T_true = invert(frame.T_world_left) @ manifold.T_world_object
        dx, dy, dz = (float(v) for v in rng.normal(0.0, 0.1, 3))
        prior = T_true @ pose_matrix(dx, dy, dz, float(rng.normal(0.0, 1.0)))
        request = ReferencingRequest((PointSetModel("manifold-1", "module-top", MODULE_TOP),), prior, 0.05, 0.4)
        t0 = time.process_time()
        result = plugin.process(StereoImages(0.0, frame.left, frame.right, frame.K, frame.baseline), request)
        times_ms.append(1e3 * (time.process_time() - t0))
        if result.recognised and result.T_cam_object is not None:
            recognised += 1
            est = invert(result.T_cam_object)[:3, 3]
            errors_mm.append(1e3 * float(np.linalg.norm(est - invert(T_true)[:3, 3])))
    camera.close()
    return {
        "scene": "worlds/sps_field.yaml, 3.6 m above manifold-1's roof top (its lifting point; 4.2 m above the roof "
                 "corners), 1200×900, fx 1000, baseline 0.25 m, ±0.2 m and ±2° around centred and aligned",
        "frames": frames,
        "recognition_percent": round(100.0 * recognised / frames, 1),
        "camera_position_error_mm": {"median": round(statistics.median(errors_mm), 1) if errors_mm else None,
                                     "max": round(max(errors_mm), 1) if errors_mm else None},
        "plugin_ms_per_pair_cpu": {"median": round(statistics.median(times_ms), 1), "max": round(max(times_ms), 1)},
        "note": "single views; the reference element fuses three (see missions/manifold_referencing.yaml)",
    }
