"""Why manifold-1's skid sets are not recognised in their fine views (issue 21 item 2): per characteristic point,
whether it is in the image and unoccluded, the Harris response there, whether a corner is detected near it, whether
a stereo point is triangulated near it and with what depth error; per view, whether the plug-in recognises the set.

    .venv/bin/python benchmarks/set_diagnosis.py [--views 6] [--out benchmarks/results/set_diagnosis.json]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path
from typing import Any

import numpy as np

os.environ.setdefault("MUJOCO_GL", "egl")


def main() -> None:
    import cv2

    from mission.agents.inspect.placement import Placement
    from mission.agents.inspect.settings import InspectSettings
    from mission.agents.inspect.viewing import SetViewer
    from mission.bench import REPO
    from mission.frames import invert, pose_matrix, transform_points
    from mission.language.loader import load_mission, load_world
    from mission.language.models import Stereo
    from mission.plugin_api import PointSetModel, ReferencingRequest, StereoImages
    from mission.sim.camera import StereoCamera
    from perception_plugins.referencing.plugin import StereoReferencingPlugin
    from perception_plugins.stereo.camera import RectifiedStereo
    from perception_plugins.stereo.pipeline import stereo_cloud

    ap = argparse.ArgumentParser()
    ap.add_argument("--views", type=int, default=6)
    ap.add_argument("--along-set", action="store_true")
    ap.add_argument("--altitude", type=float, default=None)
    ap.add_argument("--plain", action="store_true", help="the plug-in without its guided corners")
    ap.add_argument("--out", default="")
    args = ap.parse_args()
    cv2.setNumThreads(1)
    mission = load_mission(REPO / "docs" / "missions" / "manifold_inspection.yaml", environment=False)
    world = load_world(REPO / "worlds" / "sps_field.yaml")
    stereo = Stereo(width=1200, height=900, fx=1000.0, baseline=0.25, max_range=8.0)
    camera = StereoCamera(world, stereo)
    manifold = next(o for o in camera.world.scene.objects if o.id == "manifold-1")
    obj = next(o for o in mission.objects if o.id == "manifold-1")
    sets = {s.id: np.asarray(s.points, dtype=float) for s in obj.characteristic_points}
    settings = InspectSettings(**({"view_fill": float(os.environ["FILL"])} if os.environ.get("FILL") else {}))
    viewer = SetViewer(sets, (1.2, 0.9), 8.0, settings)
    plugin = StereoReferencingPlugin()
    plugin.configure({"sensors": {"stereo": {"max_range": 8.0}}, "referencing": {"guided": not args.plain}})
    rng = np.random.default_rng(7)
    report: dict[str, Any] = {}
    for set_id, pts in sets.items():
        rows = []
        for k in range(args.views):
            place = Placement(manifold.T_world_object @ pose_matrix(*rng.normal(0, 0.05, 3), rng.normal(0, 0.5)),
                              stereo.baseline)
            if args.altitude is not None:
                goal = viewer.over_set(place, set_id, args.altitude, along_set=args.along_set)
            elif args.along_set:
                goal = viewer.over_set(place, set_id, viewer.fit_altitude(set_id), along_set=True)
            else:
                goal = viewer.fine_goal(place, set_id, k)
            frame = camera.render_at(goal.north, goal.east, goal.depth, goal.heading)
            T_cam_obj = invert(frame.T_world_left) @ manifold.T_world_object
            p_cam = transform_points(T_cam_obj, pts)
            uv = p_cam[:, :2] / p_cam[:, 2:] * 1000.0 + np.array([599.5, 449.5])
            inside = (uv[:, 0] >= 0) & (uv[:, 0] < 1200) & (uv[:, 1] >= 0) & (uv[:, 1] < 900)
            seen = np.zeros(len(pts), bool)
            for i in np.flatnonzero(inside):
                u, v = int(round(uv[i, 0])), int(round(uv[i, 1]))
                patch = frame.depth_left[max(0, v - 2):v + 3, max(0, u - 2):u + 3]
                seen[i] = bool(np.nanmin(patch) > p_cam[i, 2] - 0.05)
            grey = frame.left
            harris = cv2.cornerHarris(np.float32(grey), 5, 3, 0.04)
            hmax = float(harris.max())
            geometry = RectifiedStereo.from_K(frame.K, frame.baseline, (1200, 900))
            cloud = stereo_cloud(frame.left, frame.right, geometry, detector="harris", max_features=600,
                                 max_range=8.0)
            per_point = []
            for i in range(len(pts)):
                entry: dict[str, Any] = {"in_image": bool(inside[i]), "unoccluded": bool(seen[i]),
                                         "range_m": round(float(p_cam[i, 2]), 2)}
                if inside[i]:
                    u, v = int(round(uv[i, 0])), int(round(uv[i, 1]))
                    win = harris[max(0, v - 3):v + 4, max(0, u - 3):u + 4]
                    entry["harris_rel"] = round(float(win.max()) / hmax, 4)
                    entry["harris_rank_pct"] = round(100.0 * float((harris > win.max()).mean()), 3)
                    if len(cloud):
                        d_px = np.linalg.norm(cloud.uv_left - uv[i], axis=1)
                        j = int(np.argmin(d_px))
                        entry["nearest_corner_px"] = round(float(d_px[j]), 1)
                        entry["its_3d_error_m"] = round(float(np.linalg.norm(cloud.points_cam[j] - p_cam[i])), 3)
                        entry["its_depth_error_m"] = round(float(cloud.points_cam[j, 2] - p_cam[i, 2]), 3)
                        entry["sigma_z_m"] = round(float(cloud.sigma_z[j]), 3)
                per_point.append(entry)
            prior = T_cam_obj @ pose_matrix(*rng.normal(0, 0.1, 3), rng.normal(0, 1.0))
            req = ReferencingRequest((PointSetModel("manifold-1", set_id, pts),), prior, settings.tolerance_m,
                                     settings.fine_prior_radius_m)
            res = plugin.process(StereoImages(0.0, frame.left, frame.right, frame.K, frame.baseline), req)
            err = None
            if res.recognised and res.T_cam_object is not None:
                err = float(np.max(np.linalg.norm(transform_points(res.T_cam_object, pts) - p_cam, axis=1)))
            rows.append({"view": k, "range_to_top_m": round(float(p_cam[:, 2].min()), 2),
                         "cloud_points": len(cloud), "all_unoccluded": bool(seen.all()),
                         "recognised": bool(res.recognised), "matched": res.matched, "ambiguous": res.ambiguous,
                         "max_error_m": None if err is None else round(err, 3),
                         "reason": res.details.get("reason"), "points": per_point})
        report[set_id] = rows
    camera.close()
    text = json.dumps(report, indent=1)
    if args.out:
        Path(args.out).write_text(text)
    for set_id, rows in report.items():
        rec = sum(r["recognised"] and (r["max_error_m"] or 9) < 0.1 for r in rows)
        unocc = sum(r["all_unoccluded"] for r in rows)
        print(f"== {set_id}: recognised {rec}/{len(rows)}, all points unoccluded in {unocc}/{len(rows)}")
        for r in rows:
            print(f"  view {r['view']} cloud {r['cloud_points']} rec {r['recognised']} m={r['matched']} "
                  f"err={r['max_error_m']} {r['reason'] or ''}")
            if os.environ.get("SET_DIAGNOSIS_POINTS"):
                for i, p in enumerate(r["points"]):
                    print(f"     P{i} {p}")
    sys.stdout.flush()


if __name__ == "__main__":
    main()
