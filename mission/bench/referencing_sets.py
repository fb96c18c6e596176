"""`auv bench referencing-sets` (issue 21 item 2): how often each of manifold-1's point sets is recognised in the
fine views the inspect agent takes of it, in the reference world (`worlds/sps_field.yaml`, 1200×900, fx 1000,
baseline 0.25 m), before and after the fix, and false identifications on views of bare seabed.

- **before**: the plug-in without guided corners, views as the agent took them before (3.6 m above the set's top,
  +0/0.4/0.8 m, the image's long side along the object's x-axis);
- **after**: the plug-in as configured by default (guided corners, `perception_plugins.referencing.guided`), views
  from `SetViewer.fine_goal` (the whole set in 90 % of the image, along its longer axis).

Each view is taken with the object placed 5 cm / 0.5° off (the agent's estimate after a search hit) and the
request's prior 10 cm / 1° off, as in the fine stage (tolerance 0.05 m, prior radius 0.4 m). A view *recognises*
the set when the plug-in's transform puts every point of the set within `CORRECT_M` of its true position: half the
0.3–0.4 m size of a fitting, so a pair taken with another corner of the same part counts as wrong. A set is
*unoccluded* in a view when every point projects inside the image and the rendered depth there is the point's.
Negatives: the same requests over bare seabed 30 m from the object (the prior says the set is there); every
recognition is a false identification.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any

import numpy as np

from mission.bench import REPO, check

CORRECT_M = 0.15


def _noise(rng: np.random.Generator, metres: float, degrees: float) -> tuple[float, float, float, float]:
    """North, east, depth and heading errors of a placement or prior."""
    dn, de, dd = (float(x) for x in rng.normal(0.0, metres, 3))
    return dn, de, dd, float(rng.normal(0.0, degrees))


def _unoccluded(frame: Any, points_cam: np.ndarray) -> bool:
    K = frame.K
    uv = points_cam[:, :2] / points_cam[:, 2:] * K[0, 0] + K[:2, 2]
    h, w = frame.left.shape
    if not ((uv[:, 0] >= 0) & (uv[:, 0] < w) & (uv[:, 1] >= 0) & (uv[:, 1] < h)).all():
        return False
    for (u, v), z in zip(np.rint(uv).astype(int), points_cam[:, 2], strict=True):
        if float(frame.depth_left[max(0, v - 2):v + 3, max(0, u - 2):u + 3].min()) < z - 0.05:
            return False
    return True


def run(quick: bool) -> tuple[dict[str, Any], dict[str, dict[str, Any]]]:
    os.environ.setdefault("MUJOCO_GL", "egl")
    import cv2

    from mission.agents.hover import Goal
    from mission.agents.inspect.placement import Placement
    from mission.agents.inspect.settings import InspectSettings
    from mission.agents.inspect.viewing import SetViewer
    from mission.frames import invert, pose_matrix, transform_points
    from mission.language.detectability import rate_object
    from mission.language.loader import load_mission, load_world
    from mission.language.models import Stereo
    from mission.plugin_api import PointSetModel, ReferencingRequest, StereoImages
    from mission.sim.camera import StereoCamera
    from perception_plugins.referencing.plugin import StereoReferencingPlugin

    cv2.setNumThreads(1)
    views = 4 if quick else 12
    stereo = Stereo(width=1200, height=900, fx=1000.0, baseline=0.25, max_range=8.0)
    obj = load_mission(REPO / "docs" / "missions" / "manifold_inspection.yaml", environment=False).object("manifold-1")
    sets = {s.id: np.asarray(s.points, dtype=float) for s in obj.characteristic_points}
    settings = InspectSettings()
    viewer = SetViewer(sets, (1.2, 0.9), stereo.max_range, settings)
    plugins = {}
    for name, guided in (("before", False), ("after", True)):
        plugins[name] = StereoReferencingPlugin()
        plugins[name].configure({"sensors": {"stereo": {"max_range": 8.0}}, "referencing": {"guided": guided}})

    def old_goal(place: Placement, set_id: str, k: int) -> Goal:
        return viewer.over_set(place, set_id, settings.fine_altitude_m + settings.fine_steps_m[k % 3])

    goals: dict[str, Callable[[Placement, str, int], Goal]] = {"before": old_goal, "after": viewer.fine_goal}
    rng = np.random.default_rng(21)
    table: dict[str, dict[str, Any]] = {}
    negatives = {"before": 0, "after": 0}
    negative_views = 0
    with StereoCamera(load_world(REPO / "worlds" / "sps_field.yaml"), stereo) as camera:
        truth = next(o for o in camera.world.scene.objects if o.id == "manifold-1").T_world_object
        for set_id, pts in sets.items():
            for name in ("before", "after"):
                row = table.setdefault(set_id, {}).setdefault(name, {"views": 0, "unoccluded": 0, "recognised": 0,
                                                                     "wrong": 0, "errors_m": []})
                for k in range(views):
                    place = Placement(truth @ pose_matrix(*_noise(rng, 0.05, 0.5)),
                                      stereo.baseline)
                    goal = goals[name](place, set_id, k)
                    frame = camera.render_at(goal.north, goal.east, goal.depth, goal.heading)
                    T_cam_object = invert(frame.T_world_left) @ truth
                    true_cam = transform_points(T_cam_object, pts)
                    prior = T_cam_object @ pose_matrix(*_noise(rng, 0.1, 1.0))
                    request = ReferencingRequest((PointSetModel("manifold-1", set_id, pts),), prior,
                                                 settings.tolerance_m, settings.fine_prior_radius_m)
                    images = StereoImages(0.0, frame.left, frame.right, frame.K, frame.baseline)
                    result = plugins[name].process(images, request)
                    row["views"] += 1
                    if not _unoccluded(frame, true_cam):
                        continue
                    row["unoccluded"] += 1
                    if result.recognised and result.T_cam_object is not None:
                        error = float(np.max(np.linalg.norm(transform_points(result.T_cam_object, pts) - true_cam,
                                                            axis=1)))
                        row["errors_m"].append(round(error, 3))
                        row["recognised" if error <= CORRECT_M else "wrong"] += 1
                    if name == "after" and k < (2 if quick else 4):  # negatives: bare seabed, the same request
                        negative_views += 1
                        away = camera.render_at(goal.north + 30.0, goal.east - 20.0, goal.depth + 1.5, goal.heading)
                        bare = StereoImages(0.0, away.left, away.right, away.K, away.baseline)
                        for plugin_name, plugin in plugins.items():
                            negatives[plugin_name] += plugin.process(bare, request).recognised
    for rows in table.values():
        for row in rows.values():
            row["recognition_percent"] = round(100.0 * row["recognised"] / max(row["unoccluded"], 1), 1)
    ratings = {r.set_id: {"rating": r.rating, "view_range_m": round(r.view_range_m, 2),
                          "sigma_z_cm": round(100 * r.sigma_z_m, 1)} for r in rate_object(obj, stereo)}
    results = {
        "setup": {"world": "worlds/sps_field.yaml", "sets": "docs/missions/manifold_inspection.yaml",
                  "camera": "1200×900, fx 1000, baseline 0.25 m", "views_per_set": views,
                  "correct_within_m": CORRECT_M, "placement_noise": "5 cm, 0.5°", "prior_noise": "10 cm, 1°"},
        "sets": table,
        "negatives": {"views": negative_views, "false_identifications": negatives},
        "detectability": ratings,
    }
    checks = {f"{set_id}_recognition_percent_in_unoccluded_fine_views":
              check(rows["after"]["recognition_percent"], ">= 80") for set_id, rows in table.items()}
    checks["false_identifications_on_bare_seabed"] = check(negatives["after"], "<= 0")
    checks["wrong_identifications_in_fine_views"] = check(sum(r["after"]["wrong"] for r in table.values()), "<= 0")
    return results, checks
