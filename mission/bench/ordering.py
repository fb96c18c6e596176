"""Visiting order (issue 8, seed 002 §3.4): `planners.ordering` against LKH-3 (elkai; non-commercial licence, a
benchmark reference only) on plain tours and against OR-Tools' pickup-and-delivery routing on paths with
precedence, side by side on seeded random instances.

Plain TSP: closed tours through n = 10…200 points uniform in a 1 km square; the reference is the best of 20 LKH
runs (elkai's `RUNS = 20`, distances scaled ×1000 to integers, both tours costed in float metres). Exactness:
our default answer is the Held–Karp optimum up to 12 stops besides the start, checked against brute force up to
8 stops and against the DP up to 12; the local search alone (`method="heuristic"`) is reported beside it.

With precedence: a path from a start through n stops, a fifth of them characteristic-point sets and the rest
targets, each bound to its nearest set (as `inspection_order` binds them) and visited after it. OR-Tools models
it as pickup-and-delivery: one vehicle from the start to a dummy depot reached at zero cost (an open end), each
(set, target) pair an `AddPickupAndDelivery` plus a cumul precedence on a distance dimension, integer costs ×1000
through `RegisterTransitMatrix`, first solution PATH_CHEAPEST_ARC (the insertion strategies find none or crash
when a pickup serves several deliveries), then guided local search for 30 s (3 s with --quick).

Our times are measured per instance as the smallest wall time over repeated identical runs (the solvers are
deterministic under a seed; the minimum discounts other load on the machine), with CPU time reported beside.
"""

from __future__ import annotations

import itertools
import math
import statistics
import time
from typing import Any

import numpy as np

from mission.bench import check

TSP_SIZES = (10, 20, 50, 100, 200)
PRECEDENCE_SIZES = (50, 100, 200)
SET_SHARE = 0.2
FIELD_M = 1000.0


def _timed(fn: Any, repeats: int) -> tuple[Any, float, float]:
    """Result of `fn()`, its smallest wall time and the CPU time of that run, in ms."""
    best_wall, best_cpu, out = math.inf, math.inf, None
    for _ in range(repeats):
        w0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        wall, cpu = 1000.0 * (time.perf_counter() - w0), 1000.0 * (time.process_time() - c0)
        if wall < best_wall:
            best_wall, best_cpu = wall, cpu
    return out, best_wall, best_cpu


def _points(n: int, seed: int) -> np.ndarray:
    return np.random.default_rng(1000 * n + seed).random((n, 2)) * FIELD_M


def _lkh(dist: np.ndarray) -> tuple[list[int], float]:
    try:
        import elkai
    except ImportError as exc:                                     # pragma: no cover - bench extra
        raise RuntimeError("the ordering benchmark needs elkai (LKH-3) as its reference: "
                           "pip install 'auv-mission[bench]' (or pip install elkai)") from exc
    t0 = time.perf_counter()
    tour = elkai.DistanceMatrix(np.rint(dist * 1000.0).astype(np.int64).tolist()).solve_tsp(runs=20)[:-1]
    return [int(v) for v in tour], 1000.0 * (time.perf_counter() - t0)


def _tsp(quick: bool) -> dict[str, Any]:
    from planners.ordering import distance_matrix, solve_tsp, tour_cost

    seeds = 2 if quick else 5
    repeats = 2 if quick else 3
    rows = []
    for n in TSP_SIZES:
        for seed in range(seeds):
            pts = _points(n, seed)
            dist = distance_matrix(pts)
            lkh_order, lkh_ms = _lkh(dist)
            lkh_cost = tour_cost(lkh_order, dist, closed=True)
            ours, wall, cpu = _timed(lambda pts=pts, seed=seed: solve_tsp(pts, seed=seed), repeats)
            rows.append({"n": n, "seed": seed, "ours": round(ours.cost, 3), "lkh_best_of_20": round(lkh_cost, 3),
                         "gap_percent": round(100.0 * (ours.cost / lkh_cost - 1.0), 3), "exact": ours.exact,
                         "ours_ms": round(wall, 1), "ours_cpu_ms": round(cpu, 1), "lkh_ms": round(lkh_ms, 1)})
    by_n = {}
    for n in TSP_SIZES:
        sel = [r for r in rows if r["n"] == n]
        by_n[str(n)] = {"gap_percent_max": max(r["gap_percent"] for r in sel),
                        "gap_percent_mean": round(statistics.fmean(r["gap_percent"] for r in sel), 3),
                        "ours_ms_median": round(statistics.median(r["ours_ms"] for r in sel), 1),
                        "ours_ms_max": max(r["ours_ms"] for r in sel),
                        "ours_cpu_ms_median": round(statistics.median(r["ours_cpu_ms"] for r in sel), 1),
                        "lkh_ms_median": round(statistics.median(r["lkh_ms"] for r in sel), 1)}
    return {"instances": rows, "by_n": by_n}


def _exact(quick: bool) -> dict[str, Any]:
    from planners.ordering import distance_matrix, held_karp, solve_tsp, tour_cost

    seeds = 3 if quick else 6
    brute_ok = auto_ok = True
    matches = total = 0
    for n in range(3, 14):                    # up to 12 stops besides the start
        for seed in range(seeds):
            dist = distance_matrix(_points(n, 50 + seed))
            for closed in (True, False):
                dp = held_karp(dist, 0, closed)
                if n <= 9:                    # brute force over the 8! orders of the other stops at most
                    best = min(tour_cost((0, *p), dist, closed) for p in itertools.permutations(range(1, n)))
                    brute_ok &= abs(best - dp.cost) <= 1e-9 * max(best, 1.0)
                auto = solve_tsp(cost=dist, closed=closed, seed=seed)
                auto_ok &= auto.exact and abs(auto.cost - dp.cost) <= 1e-9 * max(dp.cost, 1.0)
                heur = solve_tsp(cost=dist, closed=closed, seed=seed, method="heuristic")
                matches += heur.cost <= dp.cost * (1.0 + 1e-9)
                total += 1
    return {"dp_equals_brute_force_up_to_stops": 8, "dp_equals_brute_force": brute_ok,
            "default_is_exact_dp_up_to_stops": 12, "default_equals_dp": auto_ok,
            "heuristic_alone_finds_optimum": f"{matches}/{total}"}


def _precedence_instance(n: int, seed: int) -> tuple[np.ndarray, list[tuple[int, int]]]:
    from planners.ordering import distance_matrix

    rng = np.random.default_rng(7000 + 10 * n + seed)
    pts = rng.random((n, 2)) * FIELD_M
    k = max(1, int(round((n - 1) * SET_SHARE)))
    sets, targets = np.arange(1, k + 1), np.arange(k + 1, n)
    owner = sets[np.linalg.norm(pts[targets][:, None] - pts[sets][None], axis=-1).argmin(axis=1)]
    return distance_matrix(pts), [(int(s), int(t)) for s, t in zip(owner, targets, strict=True)]


def _ortools(dist: np.ndarray, precedences: list[tuple[int, int]], limit_s: float) -> tuple[list[int], float]:
    try:
        from ortools.constraint_solver import pywrapcp, routing_enums_pb2
    except ImportError as exc:                                     # pragma: no cover - bench extra
        raise RuntimeError("the ordering benchmark needs OR-Tools as its precedence reference: "
                           "pip install 'auv-mission[bench]' (or pip install ortools)") from exc
    n = len(dist)
    end = n                                                        # the dummy depot: an open end
    arcs = np.zeros((n + 1, n + 1), dtype=np.int64)
    arcs[:n, :n] = np.rint(dist * 1000.0).astype(np.int64)
    manager = pywrapcp.RoutingIndexManager(n + 1, 1, [0], [end])
    routing = pywrapcp.RoutingModel(manager)
    transit = routing.RegisterTransitMatrix(arcs.tolist())
    routing.SetArcCostEvaluatorOfAllVehicles(transit)
    routing.AddDimension(transit, 0, int(arcs.sum()) + 1, True, "distance")
    distance = routing.GetDimensionOrDie("distance")
    solver = routing.solver()
    for before, after in precedences:
        pickup, delivery = manager.NodeToIndex(before), manager.NodeToIndex(after)
        routing.AddPickupAndDelivery(pickup, delivery)
        solver.Add(routing.VehicleVar(pickup) == routing.VehicleVar(delivery))
        solver.Add(distance.CumulVar(pickup) <= distance.CumulVar(delivery))
    params = pywrapcp.DefaultRoutingSearchParameters()
    params.first_solution_strategy = routing_enums_pb2.FirstSolutionStrategy.PATH_CHEAPEST_ARC
    params.local_search_metaheuristic = routing_enums_pb2.LocalSearchMetaheuristic.GUIDED_LOCAL_SEARCH
    params.time_limit.FromMilliseconds(int(limit_s * 1000))
    t0 = time.perf_counter()
    solution = routing.SolveWithParameters(params)
    ms = 1000.0 * (time.perf_counter() - t0)
    if solution is None:
        raise RuntimeError(f"OR-Tools found no route (status {routing.status()})")
    index, order = routing.Start(0), []
    while not routing.IsEnd(index):
        order.append(manager.IndexToNode(index))
        index = solution.Value(routing.NextVar(index))
    return order, ms


def _precedence(quick: bool) -> dict[str, Any]:
    from planners.ordering import solve_precedence, tour_cost, violations

    limit_s = 3.0 if quick else 30.0
    repeats = 2 if quick else 3
    rows = []
    for n in PRECEDENCE_SIZES:
        dist, prec = _precedence_instance(n, 0)
        ref_order, ref_ms = _ortools(dist, prec, limit_s)
        ref_cost = tour_cost(ref_order, dist, closed=False)
        ours, wall, cpu = _timed(lambda dist=dist, prec=prec: solve_precedence(dist, 0, prec, seed=0), repeats)
        rows.append({"n": n, "sets": len({s for s, _ in prec}), "targets": len(prec),
                     "ours": round(ours.cost, 3), "ortools": round(ref_cost, 3),
                     "gap_percent": round(100.0 * (ours.cost / ref_cost - 1.0), 3),
                     "ours_ms": round(wall, 1), "ours_cpu_ms": round(cpu, 1),
                     "ortools_limit_s": limit_s, "ortools_ms": round(ref_ms, 1),
                     "violations": violations(ours.order, prec), "ortools_violations": violations(ref_order, prec)})
    return {"instances": rows}


def run(quick: bool) -> tuple[dict[str, Any], dict[str, dict[str, Any]]]:
    tsp = _tsp(quick)
    exact = _exact(quick)
    prec = _precedence(quick)
    n200 = [r for r in tsp["instances"] if r["n"] == 200]
    results = {
        "tsp": tsp,
        "exact": exact,
        "precedence": prec,
        "setup": {"tsp_sizes": list(TSP_SIZES), "precedence_sizes": list(PRECEDENCE_SIZES),
                  "set_share": SET_SHARE, "field_m": FIELD_M,
                  "lkh": "elkai DistanceMatrix(int ×1000).solve_tsp(runs=20)",
                  "ortools": "pickup-and-delivery, PATH_CHEAPEST_ARC + GUIDED_LOCAL_SEARCH",
                  "time": "ours: smallest wall time over identical repeated runs; CPU time beside"},
    }
    checks = {
        "tsp_gap_percent_vs_lkh_max": check(max(r["gap_percent"] for r in tsp["instances"]), "<= 0.5"),
        "tsp_ms_n200": check(round(statistics.median(r["ours_ms"] for r in n200), 1), "<= 100"),
        "exact_up_to_12": check(int(exact["dp_equals_brute_force"] and exact["default_equals_dp"]), ">= 1"),
        "precedence_gap_percent_vs_ortools_max": check(max(r["gap_percent"] for r in prec["instances"]), "<= 1"),
        "precedence_ms_max": check(max(r["ours_ms"] for r in prec["instances"]), "<= 1000"),
        "precedence_violations": check(sum(r["violations"] for r in prec["instances"]), "<= 0"),
    }
    return results, checks
