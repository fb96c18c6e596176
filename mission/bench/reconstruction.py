"""`auv bench reconstruction` (issue 22): 3D reconstruction of objects from rendered stereo at explore range.

Three objects made of boxes and cylinders (`mission.bench.reconstruction_scenes`: worlds/sps_field.yaml's
wellhead-x, a manifold module, a pipe spool) stand on a flat textured seabed; a 1200×900 stereo camera (fx 1000,
B 0.25 m, 1 grey level of sensor noise) looks at each from rings of views at `DISTANCE` from its centre (ranges to
the surfaces ~3–5 m). Per object:

- ours (`perception_plugins.reconstruction`): range maps, hashed TSDF fusion at the true poses, marching cubes,
  artefact removal; the same range maps fused at the poses navigation would give (`noisy_poses`); and at those
  poses refined by point-to-plane ICP against the maps already placed (`register.refine_poses`, timed apart);
- Open3D's hashed TSDF fed the same range maps and true poses, same voxel and truncation (`_open3d` says why it is
  the `VoxelBlockGrid` and not `ScalableTSDFVolume`; skipped with a message when Open3D is not installed:
  `pip install -e .[bench]`, which needs the system's libusb-1.0-0).

Figures: median and p90 distance from the mesh (area-sampled, within 0.5 m of the object's footprint) to the true
geometry (object and seabed, analytic); completeness, the share of the exposed true object surface within 5 cm of
the mesh; CPU time per frame of the range map plus its fusion (`cv2.setNumThreads(1)`: one core); the volume's
bytes and the process's peak resident memory.
"""

from __future__ import annotations

import resource
import statistics
import time
from typing import Any

import numpy as np

from mission.bench import check
from mission.bench.reconstruction_scenes import (
    SEABED_DEPTH,
    SHAPES,
    exposed_surface,
    noisy_poses,
    ring_views,
    scene_world,
    truth_parts,
    truth_sdf,
)

WIDTH, HEIGHT, FX, BASELINE = 1200, 900, 1000.0, 0.25
DISTANCE = 5.5
FULL_RINGS = ((20.0, 12), (45.0, 8), (75.0, 4))
QUICK_RINGS = ((30.0, 6), (65.0, 3))
QUICK_SHAPES = ("wellhead-x",)
"""`--quick` (under a minute): wellhead-x alone from 9 views, ours against Open3D only; the navigation-pose and ICP
variants and the other shapes are the full run's."""
MARGIN = 0.5
"""Metres around the object's box that are reconstructed too (and scored: the seabed around its foot)."""


def _evaluate(mesh: Any, parts: list[Any], exposed: np.ndarray, region: tuple[np.ndarray, np.ndarray],
              max_samples: int = 600_000) -> dict[str, Any]:
    from scipy.spatial import cKDTree

    if len(mesh.faces) == 0:
        return {"median_m": None, "p90_m": None, "completeness": 0.0, "triangles": 0}
    area = float(mesh.face_areas().sum())
    samples = mesh.sample(int(min(max(area / 1e-4, 1000), max_samples)))
    lo, hi = region
    inside = np.all((samples[:, :2] >= lo) & (samples[:, :2] <= hi), axis=1)
    err = np.abs(truth_sdf(parts, samples[inside]))
    near, _ = cKDTree(np.vstack([samples, mesh.vertices])).query(exposed, distance_upper_bound=0.05)
    return {"median_m": round(float(np.median(err)), 4), "p90_m": round(float(np.percentile(err, 90)), 4),
            "completeness": round(float(np.mean(np.isfinite(near))), 4), "triangles": int(len(mesh.faces))}


def _open3d(maps: list[Any], poses: list[np.ndarray], voxel: float, trunc: float) -> Any:
    """Open3D's hashed TSDF on the same range maps and poses, same voxel and truncation; its mesh as ours
    (`Mesh`), or None without Open3D.

    The legacy `ScalableTSDFVolume` of open3d-cpu 0.20 extracts an empty mesh here whatever it is fed (even five
    head-on views of a plane), so the anchor is `o3d.t.geometry.VoxelBlockGrid`, the voxel-hashing TSDF that
    replaces it (8³ blocks, the same projective update), with every observed voxel meshed (weight ≥ 1)."""
    import importlib

    try:  # Open3D's stubs do not type its tensors: through Any
        o3d: Any = importlib.import_module("open3d")
        o3c: Any = importlib.import_module("open3d.core")
    except ImportError:
        return None
    from perception_plugins.reconstruction import Mesh

    grid = o3d.t.geometry.VoxelBlockGrid(attr_names=("tsdf", "weight"), attr_dtypes=(o3c.float32, o3c.float32),
                                         attr_channels=((1), (1)), voxel_size=voxel, block_resolution=8,
                                         block_count=50_000, device=o3c.Device("CPU:0"))
    for rmap, T in zip(maps, poses, strict=True):
        depth = o3d.t.geometry.Image(o3c.Tensor(np.nan_to_num(rmap.depth, nan=0.0).astype(np.float32)))
        intrinsic = o3c.Tensor(rmap.K, o3c.float64)
        extrinsic = o3c.Tensor(np.linalg.inv(T), o3c.float64)
        blocks = grid.compute_unique_block_coordinates(depth, intrinsic, extrinsic, 1.0, 100.0, trunc / voxel)
        grid.integrate(blocks, depth, intrinsic, extrinsic, 1.0, 100.0, trunc / voxel)
    mesh = grid.extract_triangle_mesh(weight_threshold=1.0).to_legacy()
    v = np.asarray(mesh.vertices, dtype=float)
    return Mesh(v, np.asarray(mesh.triangles, dtype=np.int64), np.zeros(len(v), np.float32),
                np.ones(len(v), np.float32))


def measure_shape(name: str, quick: bool) -> dict[str, Any]:
    """Render the views of one object, reconstruct it three ways and score each mesh."""
    import cv2

    from mission.language.models import Stereo
    from mission.sim.camera import Degradations, StereoCamera
    from perception_plugins.reconstruction import ReconstructionSettings, fuse_range_maps, fuse_views
    from perception_plugins.reconstruction.register import refine_poses

    cv2.setNumThreads(1)
    world = scene_world(name)
    parts = truth_parts(world)
    exposed = exposed_surface(parts, spacing=0.02 if quick else 0.01)
    samples = 150_000 if quick else 600_000
    lo, hi = exposed[:, :2].min(axis=0), exposed[:, :2].max(axis=0)
    target = 0.5 * (exposed.min(axis=0) + exposed.max(axis=0))
    poses = ring_views(target, DISTANCE, QUICK_RINGS if quick else FULL_RINGS)
    camera = StereoCamera(world, Stereo(width=WIDTH, height=HEIGHT, fx=FX, baseline=BASELINE),
                          Degradations(noise_sigma=1.0, seed=1))
    frames = [camera.render(T) for T in poses]
    camera.close()
    settings = ReconstructionSettings()
    maps: list[Any] = []
    # The region explored: the object's box with a margin (the seabed to the horizon is not the object).
    bounds = (np.append(lo - MARGIN, exposed[:, 2].min() - MARGIN), np.append(hi + MARGIN, SEABED_DEPTH + MARGIN))
    ours = fuse_views(((f.left, f.right, T) for f, T in zip(frames, poses, strict=True)), frames[0].K, BASELINE,
                      settings, maps, bounds)
    region = (lo - MARGIN, hi + MARGIN)
    truth_depth = np.concatenate([f.depth_left[::2, ::2].reshape(-1) for f in frames])
    ranges = truth_depth[np.isfinite(truth_depth)]
    out: dict[str, Any] = {
        "frames": len(frames),
        "range_m": {"median": round(float(np.median(ranges)), 2), "p10": round(float(np.percentile(ranges, 10)), 2),
                    "p90": round(float(np.percentile(ranges, 90)), 2)},
        "ours": _evaluate(ours.mesh, parts, exposed, region, samples),
        "ours_before_cleaning": _evaluate(ours.raw_mesh, parts, exposed, region, samples),
        "depth_s_per_frame": round(statistics.median(ours.depth_s), 4),
        "fusion_s_per_frame": round(statistics.median(ours.fusion_s), 4),
        "extract_and_clean_s": round(ours.extract_s, 3),
        "volume_mb": round(ours.volume.nbytes / 1e6, 1),
        "volume_blocks": ours.volume.blocks,
        "dense_box_mb": round(float(np.prod(np.ptp(ours.volume.coords[:ours.volume.blocks], axis=0) + 1)) * 64 * 16
                              / 1e6, 1),
    }
    if not quick:  # the same range maps at navigation's poses, without and with ICP refinement
        nav_poses = noisy_poses(poses, seed=7)
        out["ours_navigation_poses"] = _evaluate(fuse_range_maps(maps, nav_poses, settings, bounds).mesh, parts,
                                                 exposed, region, samples)
        t0 = time.process_time()
        refined_poses = refine_poses(maps, nav_poses)
        out["icp_s_per_frame"] = round((time.process_time() - t0) / len(maps), 4)
        out["ours_navigation_poses_icp"] = _evaluate(fuse_range_maps(maps, refined_poses, settings, bounds).mesh,
                                                     parts, exposed, region, samples)
    t0 = time.process_time()
    o3d_mesh = _open3d(maps, poses, settings.voxel_m, settings.trunc_m or 4 * settings.voxel_m)
    if o3d_mesh is None:
        out["open3d"] = "skipped: Open3D is not installed (pip install -e .[bench]; it needs libusb-1.0-0)"
    else:
        out["open3d"] = _evaluate(o3d_mesh, parts, exposed, region, samples)
        out["open3d"]["fusion_s_per_frame"] = round((time.process_time() - t0) / len(frames), 4)
    return out


def run(quick: bool) -> tuple[dict[str, Any], dict[str, dict[str, Any]]]:
    shapes = {name: measure_shape(name, quick) for name in (QUICK_SHAPES if quick else SHAPES)}
    results: dict[str, Any] = {
        "scene": f"{WIDTH}x{HEIGHT}, fx {FX:g}, baseline {BASELINE} m, noise 1 grey level; views on rings "
                 f"(elevation°, count) {QUICK_RINGS if quick else FULL_RINGS} at {DISTANCE} m from the object's "
                 "centre; voxel 2 cm, truncation 8 cm; range maps matched at half resolution",
        "shapes": shapes,
        "peak_rss_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0, 1),
    }
    worst_median = max(s["ours"]["median_m"] for s in shapes.values())
    worst_complete = min(s["ours"]["completeness"] for s in shapes.values())
    per_frame = max(s["depth_s_per_frame"] + s["fusion_s_per_frame"] for s in shapes.values())
    checks = {"median_error_m": check(worst_median, "<= 0.02"),
              "completeness": check(worst_complete, ">= 0.9"),
              "seconds_per_frame": check(per_frame, "<= 0.25")}
    if all(isinstance(s["open3d"], dict) for s in shapes.values()):
        checks["median_error_vs_open3d"] = check(
            max(s["ours"]["median_m"] - s["open3d"]["median_m"] for s in shapes.values()), "<= 0.0")
        checks["completeness_vs_open3d"] = check(
            min(s["ours"]["completeness"] - s["open3d"]["completeness"] for s in shapes.values()), ">= 0.0")
    return results, checks
