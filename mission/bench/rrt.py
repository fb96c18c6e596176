"""RRT planning on the information-weighted problem (issue 6, seed 002 §2.2.1): OMPL's RRT*, Informed RRT* and
BIT* through `ompl.tools.Benchmark`.

The problem: a 120 × 80 m patch of seabed with a manifold (6 m tall), a smaller structure (4 m) and a pipeline
(1.5 m); the vehicle plans in R³ between 18 and 30 m depth (seabed at 30 m) with 2 m safety distance, from the
west edge to the east edge at 6 m altitude. The information map is the seed's I = B∗G (`planners.infomap`) of the
height map; the cost is `planners.rrt`'s information-weighted `motionCost` (discount 0.8: a metre over the most
informative ground costs a fifth of a metre over blank seabed). `ompl.tools.Benchmark` works with this Python
objective (it subclasses `PathLengthOptimizationObjective`, whose `stateCost` the benchmark also calls).

Checks:
* `solved_within_1s_percent`: share of 1 s runs that end with an exact solution, the worst of the three planners.
* `information_at_5s_vs_best_60s_percent`: from the Benchmark's progress records (best cost every 0.1 s) of 60 s
  runs: 100 × (best cost any planner reached in 60 s) / (the planner's best cost at 5 s), the median over runs, the
  worst planner. The "information" compared is the information-weighted objective the planners optimise (lower
  cost = more of the path over informative ground per metre); the raw ∫Î ds of the final paths is reported too.
  Quick runs compare 2 s with the best in 10 s.
* `validity_checks_per_s`: the validity checker (one lookup in a flattened safe-voxel list) called by OMPL's own
  motion validator on long motions (`SpaceInformation.checkMotion`, a C++ loop calling the Python callable); the
  rate seen inside a 1 s RRT* run (checker calls counted, planner overhead included) is reported beside it.
"""

from __future__ import annotations

import math
import statistics
import time
from typing import Any

import numpy as np

from mission.bench import check
from planners.infomap import information_map
from planners.rrt import ClearanceGrid, InformationField, _ompl, path_information
from planners.rrt.planning import make_planner, setup_problem

PLANNER_NAMES = ("RRTstar", "InformedRRTstar", "BITstar")
START, GOAL = (4.5, 40.5, 24.0), (115.5, 40.5, 24.0)
SAFETY = 2.0


def problem_world() -> tuple[ClearanceGrid, InformationField, np.ndarray]:
    """Clearance grid (1 m voxels, depth 18–30 m) and the information field of the height map."""
    height = np.zeros((120, 80))
    height[20:40, 30:46] = 6.0  # manifold
    height[70:88, 50:62] = 4.0  # a smaller structure
    height[55:57, 0:80] = 1.5  # pipeline across the patch
    depth_top, layers = 18.0, 12
    centres = depth_top + np.arange(layers) + 0.5
    occupied = (30.0 - centres)[None, None, :] < height[:, :, None]
    occupied[:, :, -1] = True  # the seabed layer
    grid = ClearanceGrid.from_occupancy(occupied, (0.0, 0.0, depth_top), 1.0)
    info = information_map(height, cell=1.0, nav_sigma_m=1.5)
    return grid, InformationField(info, north0=0.5, east0=0.5, cell=1.0), height


def _float(value: str) -> float:
    try:
        return float(value)
    except ValueError:
        return math.inf


def _benchmark(grid: ClearanceGrid, field: InformationField, max_time: float, runs: int, seed: int,
               on_run: Any = None) -> tuple[Any, float]:
    from ompl import tools

    problem = setup_problem(grid, START, GOAL, safety_distance=SAFETY, information=field)
    bench = tools.Benchmark(problem.setup, "information-weighted")
    si = problem.setup.getSpaceInformation()
    for name in PLANNER_NAMES:
        bench.addPlanner(make_planner(name, si))
    if on_run is not None:
        bench.setPostRunEvent(on_run)
    _ompl.seed(seed)
    t0 = time.perf_counter()
    bench.benchmark(tools.Request(max_time, 4096.0, runs, 0.1, False, False, False))
    # `bench.saveResultsToFile(path)` would write the Planner Arena log (`python -m ompl.ompl_benchmark_statistics`).
    return bench.getRecordedExperimentData(), time.perf_counter() - t0


def solved_within(grid: ClearanceGrid, field: InformationField, runs: int) -> dict[str, Any]:
    experiment, wall = _benchmark(grid, field, 1.0, runs, seed=1)
    out: dict[str, Any] = {"runs_per_planner": runs, "max_time_s": 1.0, "wall_s": round(wall, 1)}
    for planner in experiment.planners:
        rows = [r.to_dict() for r in planner.runs]
        solved = [r.get("solved BOOLEAN") == "1" and r.get("approximate solution BOOLEAN", "0") == "0" for r in rows]
        first = []
        for progress in planner.runsProgressData:
            times = [_float(p.get("time REAL", "inf")) for p in progress if math.isfinite(_cost(p))]
            first.append(min(times) if times else math.inf)
        out[_name(planner.name)] = {
            "solved_percent": round(100.0 * sum(solved) / len(rows), 1),
            "median_first_solution_by_s": round(statistics.median(first), 3) if first else None,
            "median_best_cost": round(statistics.median(_cost(r) for r in rows), 2),
        }
    return out


def anytime(grid: ClearanceGrid, field: InformationField, early: float, late: float, runs: int) -> dict[str, Any]:
    finals: dict[str, list[float]] = {}

    def on_run(planner: Any, _props: Any) -> None:
        pdef = planner.getProblemDefinition()
        if pdef.hasExactSolution():
            path = pdef.getSolutionPath()
            pts = np.array([[path.getState(i)[k] for k in range(3)] for i in range(path.getStateCount())])
            finals.setdefault(_name(planner.getName()), []).append(path_information(pts, field))

    experiment, wall = _benchmark(grid, field, late, runs, seed=2, on_run=on_run)
    at_early: dict[str, list[float]] = {}
    at_late: dict[str, list[float]] = {}
    for planner in experiment.planners:
        name = _name(planner.name)
        for progress, run_props in zip(planner.runsProgressData, planner.runs, strict=True):
            series = [(_float(p.get("time REAL", "inf")), _cost(p)) for p in progress]
            at_early.setdefault(name, []).append(min((c for t, c in series if t <= early), default=math.inf))
            # the run's final best cost too, in case the last progress sample came before the end
            final = min(min((c for _, c in series), default=math.inf), _cost(run_props.to_dict()))
            at_late.setdefault(name, []).append(final)
    best = min(min(v) for v in at_late.values())
    out: dict[str, Any] = {"early_s": early, "late_s": late, "runs_per_planner": runs, "wall_s": round(wall, 1),
                           "best_cost_seen": round(best, 2)}
    worst = math.inf
    for name in at_early:
        percents = [100.0 * best / c if math.isfinite(c) and c > 0 else 0.0 for c in at_early[name]]
        median = statistics.median(percents)
        worst = min(worst, median)
        out[name] = {"cost_at_early": [round(c, 2) for c in at_early[name]],
                     "cost_at_late": [round(c, 2) for c in at_late[name]],
                     "percent_of_best_at_early": [round(p, 1) for p in percents],
                     "median_percent": round(median, 1),
                     "information_integral_final_paths": [round(v, 1) for v in finals.get(name, [])]}
    out["worst_planner_median_percent"] = round(worst, 1)
    return out


def validity_rate(grid: ClearanceGrid, field: InformationField) -> dict[str, Any]:
    """Checker calls per second from OMPL's motion validator, and as counted inside a planning run."""
    from ompl import base

    problem = setup_problem(grid, START, GOAL, safety_distance=SAFETY, information=field)
    si = problem.setup.getSpaceInformation()
    si.setup()
    space = problem.space
    a, b = space.make_state((4.5, 75.5, 20.0)), space.make_state((115.5, 75.5, 20.0))  # a long free corridor
    per_motion = space.space.validSegmentCount(a, b)
    assert si.checkMotion(a, b)
    repeats = 40
    t0 = time.perf_counter()
    for _ in range(repeats):
        si.checkMotion(a, b)
    micro = repeats * per_motion / (time.perf_counter() - t0)
    counted = [0]
    inner = problem.checker

    def counting(s: Any) -> bool:
        counted[0] += 1
        return inner(s)

    problem.setup.setStateValidityChecker(counting)
    problem.setup.setPlanner(make_planner("RRTstar", si))
    t0 = time.perf_counter()
    problem.setup.solve(base.timedPlannerTerminationCondition(1.0))
    planning = counted[0] / (time.perf_counter() - t0)
    return {"motion_validator_checks_per_s": round(micro), "states_per_motion": int(per_motion),
            "checks_per_s_inside_rrtstar_run": round(planning), "checks_in_1s_rrtstar_run": counted[0],
            "grid_voxels": int(np.prod(grid.shape))}


def _cost(record: dict[str, str]) -> float:
    """The best cost of a Benchmark record (RRT* logs it as REAL, BIT* as DOUBLE)."""
    return _float(record.get("best cost REAL", record.get("best cost DOUBLE", "inf")))


def _name(planner_name: str) -> str:
    """Our name of a planner from the Benchmark's ('geometric_InformedRRTstar', 'geometric_kBITstar')."""
    name = planner_name.removeprefix("geometric_")
    return "BITstar" if name == "kBITstar" else name


def run(quick: bool) -> tuple[dict[str, Any], dict[str, dict[str, Any]]]:
    grid, field, _ = problem_world()
    validity = validity_rate(grid, field)
    solved = solved_within(grid, field, runs=4 if quick else 20)
    early, late = (2.0, 10.0) if quick else (5.0, 60.0)
    quality = anytime(grid, field, early, late, runs=1 if quick else 3)
    results = {
        "problem": "120x80 m seabed, depth 18-30 m, 1 m voxels; manifold 6 m, structure 4 m, pipeline 1.5 m; "
                   "R3, safety 2 m; information-weighted cost (discount 0.8) from I = B*G of the height map",
        "harness": "ompl.tools.Benchmark (Python objective subclassing PathLengthOptimizationObjective)",
        "start": START, "goal": GOAL,
        "validity": validity,
        "solved_within_1s": solved,
        "anytime": quality,
        "note": "quick: 2 s vs the best in 10 s, 1 run per planner; full: 5 s vs 60 s, 3 runs" if quick else
                "5 s vs the best in 60 s, 3 runs per planner",
    }
    worst_solved = min(solved[name]["solved_percent"] for name in PLANNER_NAMES)
    checks = {
        "solved_within_1s_percent": check(worst_solved, ">= 100"),
        "information_at_5s_vs_best_60s_percent": check(quality["worst_planner_median_percent"], ">= 95"),
        "validity_checks_per_s": check(validity["motion_validator_checks_per_s"], ">= 500000"),
    }
    return results, checks
