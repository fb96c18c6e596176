"""Identification and referencing (issue 3, seed 002 §3.1–3.3): ours (consistency graph, anchor triangles,
maximum clique, robust Kabsch) against the paper's exhaustive subset search, open3d's FPFH + RANSAC and open3d's
ICP started from a database pose, side by side on the same seeded cases.

The seeded cases and their ground truth are built by `mission.bench.referencing_cases`.

Success (issue 3): at least 3 correct pairs and no wrong pair. The transform errors are those of the vehicle
(camera) pose in the object frame: rotation angle, and the camera position (T_model_cloud's translation).
"""

from __future__ import annotations

import math
import statistics
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mission.bench import check
from mission.bench.referencing_cases import (
    EXCLUSION,
    SIGMA,
    TOLERANCE,
    Case,
    ideal_transform,
    pose_errors,
    random_case,
    score_pairs,
)
from mission.bench.referencing_images import run_images

Array = NDArray[np.float64]

def _stats(values: list[float], scale: float = 1.0, digits: int = 4) -> dict[str, float | None]:
    if not values:
        return {"p50": None, "p99": None, "max": None}
    arr = np.asarray(values) * scale
    return {"p50": round(float(np.median(arr)), digits), "p99": round(float(np.quantile(arr, 0.99)), digits),
            "max": round(float(arr.max()), digits)}


def _pairs_from_transform(case: Case, T: Array, tolerance: float) -> list[tuple[int, int]]:
    """What a transform-only method identifies: each model point's nearest cloud point within tolerance."""
    from scipy.spatial import cKDTree

    d, j = cKDTree(case.cloud).query(case.model @ T[:3, :3].T + T[:3, 3], distance_upper_bound=tolerance)
    best: dict[int, tuple[int, float]] = {}
    for k in np.flatnonzero(np.isfinite(d)).tolist():
        if int(j[k]) not in best or d[k] < best[int(j[k])][1]:
            best[int(j[k])] = (k, float(d[k]))
    return sorted((k, cj) for cj, (k, _) in best.items())


@dataclass
class _Tally:
    """Outcomes of one method over cases."""

    cases: int = 0
    successes: int = 0
    recognised: int = 0
    wrong_pair_cases: int = 0
    ambiguous: int = 0
    over_budget: int = 0
    rotation_deg: list[float] | None = None
    centroid_m: list[float] | None = None
    camera_m: list[float] | None = None
    origin_m: list[float] | None = None
    ms: list[float] | None = None
    ideal_rotation_deg: list[float] | None = None

    def __post_init__(self) -> None:
        self.rotation_deg, self.centroid_m, self.camera_m, self.origin_m, self.ms = [], [], [], [], []
        self.ideal_rotation_deg = []

    def add(self, case: Case, pairs: list[tuple[int, int]], T: Array | None, ms: float,
            ambiguous: bool = False, exact: bool = True) -> bool:
        assert self.rotation_deg is not None and self.centroid_m is not None and self.camera_m is not None
        assert self.origin_m is not None and self.ms is not None
        correct, wrong = score_pairs(pairs, case.truth)
        ok = correct >= 3 and wrong == 0
        self.cases += 1
        self.successes += ok
        self.recognised += len(pairs) >= 3
        self.wrong_pair_cases += wrong > 0
        self.ambiguous += ambiguous
        self.over_budget += not exact
        self.ms.append(ms)
        if ok and T is not None:
            angle, camera = pose_errors(T, case.T_cloud_model)
            centre = case.model.mean(axis=0)
            self.rotation_deg.append(angle)
            self.camera_m.append(camera)
            self.centroid_m.append(float(np.linalg.norm((T[:3, :3] - case.T_cloud_model[:3, :3]) @ centre
                                                        + T[:3, 3] - case.T_cloud_model[:3, 3])))
            self.origin_m.append(float(np.linalg.norm(T[:3, 3] - case.T_cloud_model[:3, 3])))
            assert self.ideal_rotation_deg is not None
            self.ideal_rotation_deg.append(pose_errors(ideal_transform(case), case.T_cloud_model)[0])
        return ok

    def summary(self) -> dict[str, Any]:
        assert self.rotation_deg is not None and self.centroid_m is not None and self.camera_m is not None
        assert self.origin_m is not None and self.ms is not None
        n = max(self.cases, 1)
        return {
            "cases": self.cases,
            "success_percent": round(100.0 * self.successes / n, 2),
            "recognised_percent": round(100.0 * self.recognised / n, 2),
            "cases_with_a_wrong_pair": self.wrong_pair_cases,
            "ambiguous_cases": self.ambiguous,
            "cases_stopped_by_the_time_budget": self.over_budget,
            "rotation_error_deg": _stats(self.rotation_deg, digits=3),
            "rotation_error_of_least_squares_on_all_true_pairs_deg": _stats(self.ideal_rotation_deg or [], digits=3),
            "translation_error_at_model_centroid_cm": _stats(self.centroid_m, 100.0, 2),
            "camera_position_error_in_object_frame_cm": _stats(self.camera_m, 100.0, 2),
            "object_origin_error_in_camera_frame_cm": _stats(self.origin_m, 100.0, 2),
            "time_ms": _stats(self.ms, digits=1),
        }


GRID = [(8, 100), (8, 250), (8, 500), (8, 1000), (12, 250), (12, 500), (12, 1000), (20, 250), (20, 500),
        (20, 1000), (40, 500), (40, 1000)]


def _ours(cases: list[tuple[int, int, Case]]) -> tuple[_Tally, dict[tuple[int, int], _Tally], list[float]]:
    from perception_plugins.referencing import reference

    overall = _Tally()
    by_size: dict[tuple[int, int], _Tally] = {}
    cpu_n20_m500: list[float] = []
    for n, m, case in cases:
        t0, c0 = time.perf_counter(), time.process_time()
        result = reference(case.model, case.cloud, TOLERANCE)
        wall, cpu = 1000 * (time.perf_counter() - t0), 1000 * (time.process_time() - c0)
        overall.add(case, result.pairs, result.T_cloud_model, wall, result.ambiguous, result.exact)
        by_size.setdefault((n, m), _Tally()).add(case, result.pairs, result.T_cloud_model, wall, result.ambiguous,
                                                 result.exact)
        if (n, m) == (20, 500):
            cpu_n20_m500.append(cpu)
    return overall, by_size, cpu_n20_m500


def _exhaustive(seeds: int) -> dict[str, Any]:
    """The paper's search against ours on clouds it can afford: N = 6 points (5–6 visible), M = 8, 12, 16."""
    from perception_plugins.referencing import exhaustive_identify, identify

    rows = []
    for m in (8, 12, 16):
        paper, ours = _Tally(), _Tally()
        agree = 0
        t_paper, t_ours = [], []
        for seed in range(seeds):
            case = random_case(10_000 + 100 * m + seed, 6, m)
            t0 = time.process_time()
            pairs_paper = exhaustive_identify(case.model, case.cloud, TOLERANCE)
            t_paper.append(1000 * (time.process_time() - t0))
            t0 = time.process_time()
            pairs_ours = identify(case.model, case.cloud, TOLERANCE)
            t_ours.append(1000 * (time.process_time() - t0))
            paper.add(case, pairs_paper, None, t_paper[-1])
            ours.add(case, pairs_ours, None, t_ours[-1])
            agree += pairs_paper == pairs_ours
        rows.append({
            "N": 6, "M": m, "cases": seeds,
            "paper_success_percent": paper.summary()["success_percent"],
            "ours_success_percent": ours.summary()["success_percent"],
            "same_pairs_percent": round(100.0 * agree / max(seeds, 1), 1),
            "paper_median_cpu_ms": round(statistics.median(t_paper), 2),
            "ours_median_cpu_ms": round(statistics.median(t_ours), 2),
            "speed_ratio_paper_over_ours": round(statistics.median(t_paper) / max(statistics.median(t_ours), 1e-6), 1),
        })
    comparisons = {f"N={n}, M={m}": f"{sum(math.comb(n, k) * math.comb(m, k) for k in range(3, min(n, m) + 1)):.3g}"
                   for n, m in [(6, 16), (8, 100), (20, 500), (40, 1000)]}
    return {"by_cloud_size": rows, "paper_subset_pairs_to_compare_worst_case": comparisons}


def _open3d(cases: list[tuple[int, int, Case]], quick: bool) -> dict[str, Any]:
    """open3d FPFH + RANSAC (global) and ICP from a database pose 1–3 m and 2–5° off (local), on the same cases."""
    try:
        import open3d as o3d
    except ImportError as exc:                             # a benchmark extra, not a runtime need
        return {"skipped": f"open3d is not installed ({exc}); pip install 'auv-mission[bench]'"}
    from scipy.spatial.transform import Rotation

    reg: Any = o3d.pipelines.registration                 # its stubs lag behind its defaults
    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)

    def cloud_of(points: Array) -> Any:
        pc = o3d.geometry.PointCloud()
        pc.points = o3d.utility.Vector3dVector(points)
        pc.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=1.5, max_nn=30))
        return pc

    def fpfh(pc: Any) -> Any:
        return reg.compute_fpfh_feature(pc, o3d.geometry.KDTreeSearchParamHybrid(radius=3.0, max_nn=100))

    ransac, icp = _Tally(), _Tally()
    iterations = 20_000 if quick else 100_000
    for i, (_, _, case) in enumerate(cases):
        src, dst = cloud_of(case.model), cloud_of(case.cloud)
        t0 = time.perf_counter()
        result = reg.registration_ransac_based_on_feature_matching(
            src, dst, fpfh(src), fpfh(dst), False, 3 * TOLERANCE, reg.TransformationEstimationPointToPoint(False), 3,
            [reg.CorrespondenceCheckerBasedOnEdgeLength(0.9), reg.CorrespondenceCheckerBasedOnDistance(3 * TOLERANCE)],
            reg.RANSACConvergenceCriteria(iterations, 0.999))
        ms = 1000 * (time.perf_counter() - t0)
        T = np.asarray(result.transformation)
        ransac.add(case, _pairs_from_transform(case, T, TOLERANCE), T, ms)
        rng = np.random.default_rng(20_000 + i)
        direction = rng.normal(size=3)
        axis = rng.normal(size=3)
        init = case.T_cloud_model.copy()
        init[:3, :3] = Rotation.from_rotvec(np.radians(rng.uniform(2, 5)) * axis / np.linalg.norm(axis)).as_matrix() \
            @ init[:3, :3]
        init[:3, 3] += rng.uniform(1, 3) * direction / np.linalg.norm(direction)
        t0 = time.perf_counter()
        T = init
        for threshold in (3.0, 1.0, 0.3, TOLERANCE):          # coarse to fine, to give ICP its best chance
            T = np.asarray(reg.registration_icp(src, dst, threshold, T, reg.TransformationEstimationPointToPoint(),
                                                reg.ICPConvergenceCriteria(max_iteration=50)).transformation)
        icp.add(case, _pairs_from_transform(case, T, TOLERANCE), T, 1000 * (time.perf_counter() - t0))
    return {
        "fpfh_ransac": {"settings": f"normals r=1.5 m, FPFH r=3 m, ransac_n=3, {iterations} iterations, "
                                    f"max correspondence {3 * TOLERANCE} m", **ransac.summary()},
        "icp": {"settings": "point-to-point from the database pose (1–3 m, 2–5° off), thresholds 3, 1, 0.3, 0.1 m",
                **icp.summary()},
    }


def run(quick: bool) -> tuple[dict[str, Any], dict[str, dict[str, Any]]]:
    per_size = 10 if quick else 100
    baseline_per_size = 2 if quick else 10
    cases = [(n, m, random_case(1000 * n + m + seed, n, m)) for n, m in GRID for seed in range(per_size)]
    extra_timing = 20 if quick else 100                     # more N = 20, M = 500 cases for the median time
    timing = [(20, 500, random_case(500_000 + seed, 20, 500)) for seed in range(extra_timing)]
    overall, by_size, cpu = _ours(cases)                    # every size weighs the same in the success rate
    timed, _, cpu_extra = _ours(timing)
    ours = overall.summary()
    n20 = by_size[(20, 500)]
    assert n20.ms is not None and timed.ms is not None
    assert overall.rotation_deg is not None and overall.centroid_m is not None
    median_ms = statistics.median(n20.ms + timed.ms)
    median_cpu = statistics.median(cpu + cpu_extra)
    baseline_cases = [c for i, c in enumerate(cases) if i % per_size < baseline_per_size]
    images = run_images(quick)
    results = {
        "setup": {
            "object": "skid 7–9 × 4–6 × 0.4–0.8 m with a module (2.5–4.5 × 2–3.5 × 1–2.5 m) and a small box on top",
            "model": "N points on the visible faces (a third at box corners), ≥ 0.4 m apart",
            "visible": "60–100 % of N, at least 5", "noise_sigma_m": SIGMA, "tolerance_m": TOLERANCE,
            "outliers": "half on the seabed (±3 m around the skid, 5 cm relief), half on the object's faces, "
                        f"none within {EXCLUSION} m of a model point's true position",
            "grid_n_m": GRID, "cases_per_size": per_size, "extra_n20_m500_timing_cases": extra_timing,
            "success": "≥ 3 correct pairs and no wrong pair",
        },
        "ours": ours,
        "ours_by_size": [{"N": n, "M": m, **{k: v for k, v in t.summary().items()
                                             if k in ("cases", "success_percent", "cases_with_a_wrong_pair",
                                                      "ambiguous_cases", "cases_stopped_by_the_time_budget",
                                                      "time_ms")}}
                         for (n, m), t in sorted(by_size.items())],
        "extra_n20_m500_cases_success_percent": timed.summary()["success_percent"],
        "median_ms_n20_m500": {"cpu": round(median_cpu, 1), "wall": round(median_ms, 1),
                               "cases": n20.cases + timed.cases,
                               "note": "the check uses CPU time of this process (one thread): on a shared machine "
                                       "wall time also counts other processes' turns"},
        "checks_statistics": {
            "rotation_error_deg_p99": "99th percentile over successful cases (the max is in `ours`; its tail is "
                                      "the least-squares noise floor, see rotation_error_of_least_squares_on_all_"
                                      "true_pairs_deg)",
            "translation_error_over_sigma": "max over successful cases of |T·c − T_true·c| at the model centroid c, "
                                            "divided by σ (camera-position errors, lever-armed by the rotation "
                                            "error, are in `ours`)",
        },
        "exhaustive_paper": _exhaustive(4 if quick else 20),
        "images": images,
        **_open3d(baseline_cases, quick),
    }
    rotation_p99 = float(np.quantile(overall.rotation_deg, 0.99)) if overall.rotation_deg else math.inf
    images_ms = images["plugin_ms_per_pair_cpu"]["median"]
    checks = {
        "success_percent": check(ours["success_percent"], ">= 99"),
        "rotation_error_deg_p99": check(round(rotation_p99, 3), "< 1"),
        "translation_error_over_sigma": check(round(max(overall.centroid_m, default=math.inf) / SIGMA, 2), "< 2"),
        "median_ms_n20_m500": check(round(median_cpu, 1), "<= 50"),
        "images_ms_per_stereo_pair": check(images_ms, "<= 100"),
    }
    return results, checks
