"""Stereo speed and accuracy: rendering pairs of seed 000's virtual scene and turning them into clouds.

Seed 000 §4 flies 3.6 m above the object with 1200×900 images; issue 3 asks for ≤ 100 ms per stereo pair on one
core and for our stereo code to be checked on real pixels (Middlebury "Motorcycle", shipped with scikit-image with
its ground-truth disparity and calibration). This benchmark measures, on one core:

- rendering: ms per left/right pair at 1200×900 of `worlds/sps_field.yaml` from 3.6 m above manifold-1's roof
  (`mission.sim.camera.StereoCamera`, EGL or OSMesa software rendering);
- `perception_plugins.stereo.stereo_cloud` per detector (SIFT, ORB, Harris): ms per pair including detection,
  matching, sub-pixel refinement and triangulation, and the cloud's depth error against the rendered depth;
- Middlebury: median |d − d_true| (px) at our matched points and the median relative depth error, per detector.

"One core" is enforced by running the measurements in a child process pinned to one CPU
(`os.sched_setaffinity`) with `LP_NUM_THREADS=1` (Mesa's llvmpipe), `cv2.setNumThreads(1)` and single-threaded
BLAS. The `stereo_cloud_ms_1200x900` check takes the fastest detector whose clouds stay within 1 % median depth
error on the rendered pairs, and `results` names it; every detector's time is reported beside it. The Middlebury
check uses `stereo_cloud`'s default detector (SIFT).
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import time
from typing import Any, Literal

import numpy as np

from mission.bench import REPO, check

ALTITUDE = 3.6
WIDTH, HEIGHT, FX, BASELINE = 1200, 900, 1000.0, 0.25
MAX_RANGE = 8.0
DETECTORS: tuple[Literal["sift", "orb", "harris"], ...] = ("sift", "orb", "harris")
MIDDLEBURY = {"f": 994.978, "cx": 311.193, "cy": 254.877, "doffs": 31.086, "baseline_m": 0.193001}
"""Calibration of the 4×-downsampled Motorcycle pair, from `skimage.data.stereo_motorcycle`'s docstring."""


def _poses(camera: Any, count: int) -> list[tuple[float, float, float, float]]:
    """Vehicle poses ALTITUDE above manifold-1's roof: over the roof at spread offsets and headings."""
    from mission.frames import transform_points

    manifold = next(o for o in camera.world.scene.objects if o.id == "manifold-1")
    rng = np.random.default_rng(0)
    poses = []
    for k in range(count):
        x, y = (4.0, 2.5) if k == 0 else (4.0 + rng.uniform(-1.0, 1.0), 2.5 + rng.uniform(-0.8, 0.8))
        p = transform_points(manifold.T_world_object, np.array([[x, y, -2.0]]))[0]
        heading = 33.5 if k == 0 else float(rng.uniform(0.0, 360.0))
        poses.append((float(p[0]), float(p[1]), float(p[2] - ALTITUDE), heading))
    return poses


def _cloud_stats(frame: Any, cloud: Any) -> tuple[float, float]:
    """(median relative depth error, 95th percentile of |error| / σ_Z) against the rendered depth."""
    u = np.clip(np.rint(cloud.uv_left[:, 0]).astype(int), 0, WIDTH - 1)
    v = np.clip(np.rint(cloud.uv_left[:, 1]).astype(int), 0, HEIGHT - 1)
    truth = frame.depth_left[v, u].astype(float)
    err = np.abs(cloud.points_cam[:, 2] - truth)
    return float(np.median(err / truth)), float(np.percentile(err / cloud.sigma_z, 95))


def _middlebury(quick: bool) -> dict[str, Any]:
    import cv2
    import skimage.data

    from perception_plugins.stereo import RectifiedStereo, stereo_cloud

    left, right, disparity = skimage.data.stereo_motorcycle()  # type: ignore[no-untyped-call,unused-ignore]
    grey_l, grey_r = (cv2.cvtColor(im, cv2.COLOR_RGB2GRAY) for im in (left, right))
    m = MIDDLEBURY
    geometry = RectifiedStereo(m["f"], m["f"], m["cx"], m["cy"], m["baseline_m"], (left.shape[1], left.shape[0]),
                               m["doffs"])
    out: dict[str, Any] = {"pair": "Middlebury 2014 Motorcycle, 741x500 (scikit-image, downsampled 4x)",
                           "calibration": m, "depth": "Z = f*B/(d + doffs)", "detectors": {}}
    for detector in DETECTORS:
        times = []
        for _ in range(1 if quick else 3):
            t0 = time.perf_counter()
            cloud = stereo_cloud(grey_l, grey_r, geometry, detector, 2000)
            times.append(1000.0 * (time.perf_counter() - t0))
        u = np.rint(cloud.uv_left).astype(int)
        truth = disparity[u[:, 1], u[:, 0]]
        known = np.isfinite(truth)
        error = np.abs(cloud.disparity[known] - truth[known])
        z_true = geometry.depth(truth[known])
        rel = np.abs(cloud.points_cam[known, 2] - z_true) / z_true
        out["detectors"][detector] = {
            "points": len(cloud), "points_with_truth": int(known.sum()),
            "median_disparity_error_px": round(float(np.median(error)), 4),
            "p90_disparity_error_px": round(float(np.percentile(error, 90)), 3),
            "share_over_3px": round(float(np.mean(error > 3.0)), 4),
            "median_relative_depth_error": round(float(np.median(rel)), 5),
            "ms": round(statistics.median(times), 1)}
    return out


def measure(quick: bool) -> dict[str, Any]:
    """All measurements, in this process (the child of `run`, pinned to one core)."""
    import cv2

    from mission.language.loader import load_world
    from mission.language.models import Stereo
    from mission.sim.camera import StereoCamera
    from perception_plugins.stereo import RectifiedStereo, stereo_cloud

    cv2.setNumThreads(1)
    t0 = time.perf_counter()
    camera = StereoCamera(load_world(REPO / "worlds" / "sps_field.yaml"),
                          Stereo(width=WIDTH, height=HEIGHT, fx=FX, baseline=BASELINE))
    init_s = time.perf_counter() - t0
    poses = _poses(camera, 4 if quick else 20)
    camera.render_at(*poses[0])  # warm-up: shaders, texture upload
    frames, render_ms = [], []
    for pose in poses:
        t0 = time.perf_counter()
        frames.append(camera.render_at(*pose))
        render_ms.append(1000.0 * (time.perf_counter() - t0))
    camera.close()
    geometry = RectifiedStereo.from_K(frames[0].K, BASELINE, (WIDTH, HEIGHT))
    clouds: dict[str, Any] = {}
    for detector in DETECTORS:
        stereo_cloud(frames[0].left, frames[0].right, geometry, detector, 2000, max_range=MAX_RANGE)  # warm-up
        ms, points, rel, tail = [], [], [], []
        for frame in frames[:2] if quick else frames:
            t0 = time.perf_counter()
            cloud = stereo_cloud(frame.left, frame.right, geometry, detector, 2000,
                                 max_range=MAX_RANGE)
            ms.append(1000.0 * (time.perf_counter() - t0))
            r, t = _cloud_stats(frame, cloud)
            points.append(len(cloud))
            rel.append(r)
            tail.append(t)
        clouds[detector] = {"ms_median": round(statistics.median(ms), 1), "ms_max": round(max(ms), 1),
                            "pairs": len(ms), "points_median": int(statistics.median(points)),
                            "median_relative_depth_error": round(statistics.median(rel), 6),
                            "p95_abs_error_over_sigma_z": round(statistics.median(tail), 3)}
    return {
        "scene": {"world": "worlds/sps_field.yaml", "object": "manifold-1", "altitude_above_roof_m": ALTITUDE,
                  "image": [WIDTH, HEIGHT], "fx_px": FX, "baseline_m": BASELINE, "max_range_m": MAX_RANGE,
                  "poses": len(poses)},
        "render": {"camera_build_s": round(init_s, 2), "pairs": len(render_ms),
                   "ms_per_pair_median": round(statistics.median(render_ms), 1),
                   "ms_per_pair_max": round(max(render_ms), 1),
                   "includes": "two renders (RGB + depth read-back), grey conversion, depth to metres"},
        "stereo_cloud": clouds,
        "middlebury": _middlebury(quick),
    }


def _pin_to_one_core() -> None:
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})


def run(quick: bool) -> tuple[dict[str, Any], dict[str, dict[str, Any]]]:
    env = {**os.environ, "LP_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
           "MKL_NUM_THREADS": "1", "OPENCV_FOR_THREADS_NUM": "1"}
    env.setdefault("MUJOCO_GL", "egl")
    args = [sys.executable, "-m", "mission.bench.stereo", "--child"] + (["--quick"] if quick else [])
    done = subprocess.run(args, env=env, cwd=REPO, capture_output=True, text=True, timeout=600, check=False,
                          preexec_fn=_pin_to_one_core if hasattr(os, "sched_setaffinity") else None)
    if done.returncode != 0:
        raise RuntimeError(f"stereo benchmark child failed:\n{done.stderr[-4000:]}")
    results: dict[str, Any] = json.loads(done.stdout.strip().splitlines()[-1])
    results["one_core"] = ("child process pinned to one CPU (sched_setaffinity), LP_NUM_THREADS=1, "
                           "cv2.setNumThreads(1), single-threaded BLAS")
    accurate = {d: r for d, r in results["stereo_cloud"].items() if r["median_relative_depth_error"] < 0.01}
    fastest = min(accurate, key=lambda d: accurate[d]["ms_median"]) if accurate else "sift"
    results["check_detector"] = fastest
    results["notes"] = [
        "SURF (the seeds' detector) is patented/nonfree and absent from the OpenCV wheels: SIFT, ORB and Harris "
        "stand in.",
        "stereo_cloud_ms_1200x900 uses the fastest detector within 1 % median depth error on the rendered pairs; "
        "SIFT's own time is in stereo_cloud.sift.",
    ]
    checks = {
        "stereo_cloud_ms_1200x900": check(results["stereo_cloud"][fastest]["ms_median"], "<= 100"),
        "middlebury_median_disparity_error_px": check(
            results["middlebury"]["detectors"]["sift"]["median_disparity_error_px"], "<= 1.0"),
    }
    return results, checks


if __name__ == "__main__":
    if "--child" in sys.argv:
        print(json.dumps(measure("--quick" in sys.argv)))
    else:
        print(json.dumps(run("--quick" in sys.argv), indent=2))
