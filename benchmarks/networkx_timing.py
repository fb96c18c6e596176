"""networkx against the hand-written graph code it could replace (issue 26): timings and the ratio nx / ours.

Run: `.venv/bin/python benchmarks/networkx_timing.py` (one core is enough; about a minute). It prints one line per
comparison; the module docstrings of `planners.coverage.routes`, `planners.ordering.tsp` and `mission.strategy`
quote the figures and say which was kept.

1. Transit routing (`planners.coverage.routes.Router`): all-pairs shortest paths (distances and next hops) over
   the visibility graph of the grown zones' corners, for the coverage benchmark's seeded scenes with zones:
   our vectorised Floyd–Warshall against `networkx.all_pairs_dijkstra` (converted to the same arrays).
2. Precedence graph (`planners.ordering.tsp`): the predecessor/successor lists plus a cycle check, against a
   `networkx.DiGraph` with `is_directed_acyclic_graph`; also against a whole `solve_precedence` call.
3. The strategic level's graph of objects (`mission.strategy.order_route`): our exact open path
   (`solve_tsp`, Held–Karp up to 12 objects) against `networkx.approximation.christofides` on the complete
   graph (the cycle from the vehicle's position less its return leg): time and path length.
"""

from __future__ import annotations

import math
import random
import statistics
import time
from collections.abc import Callable
from typing import Any

import networkx as nx
import numpy as np


def best_of(fn: Callable[..., Any], *args: Any, repeat: int = 5) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn(*args)
        times.append(time.perf_counter() - t0)
    return min(times)


# ----------------------------------------------------------------------------------------------- 1. routing
def _visibility_edges(router: Any) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
    n = len(router.nodes)
    i, j = np.triu_indices(n, 1)
    ok = router.clear(router.nodes[i], router.nodes[j])
    d = np.linalg.norm(router.nodes[i] - router.nodes[j], axis=1)
    return n, i[ok], j[ok], d[ok]


def floyd_warshall_numpy(n: int, i: np.ndarray, j: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The loop of `Router.__init__`, as it is there."""
    dist = np.full((n, n), np.inf)
    nxt = np.full((n, n), -1, dtype=np.int64)
    dist[i, j] = dist[j, i] = d
    nxt[i, j], nxt[j, i] = j, i
    np.fill_diagonal(dist, 0.0)
    np.fill_diagonal(nxt, np.arange(n))
    for k in range(n):
        alt = dist[:, k : k + 1] + dist[k : k + 1, :]
        better = alt < dist
        if better.any():
            dist = np.where(better, alt, dist)
            nxt = np.where(better, nxt[:, k : k + 1], nxt)
    return dist, nxt


def dijkstra_networkx(n: int, i: np.ndarray, j: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    graph = nx.Graph()
    graph.add_nodes_from(range(n))
    graph.add_weighted_edges_from(zip(i.tolist(), j.tolist(), d.tolist(), strict=True))
    dist = np.full((n, n), np.inf)
    nxt = np.full((n, n), -1, dtype=np.int64)
    for a, (lengths, paths) in nx.all_pairs_dijkstra(graph):
        for b, length in lengths.items():
            dist[a, b] = length
            path = paths[b]
            nxt[a, b] = path[1] if len(path) > 1 else a
    return dist, nxt


def routing() -> None:
    from mission.bench.coverage import random_case
    from planners.coverage.scene import Scene

    ours, theirs, sizes = [], [], []
    for seed in range(60):
        case = random_case(seed)
        if not case["zones"]:
            continue
        scene = Scene.build(case["area"], case["zones"], 6.0, 2.0, case["swath"])
        n, i, j, d = _visibility_edges(scene.router)
        if n < 2:
            continue
        a_dist, _ = floyd_warshall_numpy(n, i, j, d)
        b_dist, _ = dijkstra_networkx(n, i, j, d)
        assert np.allclose(a_dist, b_dist), "the two all-pairs computations disagree"
        ours.append(best_of(floyd_warshall_numpy, n, i, j, d))
        theirs.append(best_of(dijkstra_networkx, n, i, j, d))
        sizes.append(n)
    ratio = [t / o for o, t in zip(ours, theirs, strict=True)]
    print(f"routing: {len(sizes)} scenes, {min(sizes)}-{max(sizes)} corners; all-pairs per scene "
          f"ours {1e3 * statistics.median(ours):.3f} ms, networkx {1e3 * statistics.median(theirs):.3f} ms "
          f"(median); ratio nx/ours median {statistics.median(ratio):.1f}, min {min(ratio):.1f}, "
          f"max {max(ratio):.1f}")


# -------------------------------------------------------------------------------------------- 2. precedence
def precedence_lists(n: int, precedences: list[tuple[int, int]]) -> tuple[list[list[int]], list[list[int]]]:
    """Our lists and a Kahn cycle check (what `tsp._precedence_lists` and `construct` do between them)."""
    need: list[list[int]] = [[] for _ in range(n)]
    follow: list[list[int]] = [[] for _ in range(n)]
    for before, after in precedences:
        need[after].append(before)
        follow[before].append(after)
    waiting = [len(v) for v in need]
    ready = [v for v in range(n) if waiting[v] == 0]
    seen = 0
    while ready:
        u = ready.pop()
        seen += 1
        for w in follow[u]:
            waiting[w] -= 1
            if waiting[w] == 0:
                ready.append(w)
    if seen != n:
        raise ValueError("cycle")
    return need, follow


def precedence_networkx(n: int, precedences: list[tuple[int, int]]) -> tuple[list[list[int]], list[list[int]]]:
    graph = nx.DiGraph()
    graph.add_nodes_from(range(n))
    graph.add_edges_from(precedences)
    if not nx.is_directed_acyclic_graph(graph):
        raise ValueError("cycle")
    return [list(graph.predecessors(v)) for v in range(n)], [list(graph.successors(v)) for v in range(n)]


def precedence() -> None:
    from planners.ordering import distance_matrix, solve_precedence

    for n in (30, 100, 300):
        rng = random.Random(n)
        sets = list(range(1, n, 4))                        # a set, then the targets referenced to it
        precedences = [(s, t) for s in sets for t in range(s + 1, min(s + 4, n))]
        ours = best_of(precedence_lists, n, precedences, repeat=20)
        theirs = best_of(precedence_networkx, n, precedences, repeat=20)
        points = [(rng.uniform(0, 200), rng.uniform(0, 200)) for _ in range(n)]
        cost = distance_matrix(points)
        t0 = time.perf_counter()
        solve_precedence(cost, 0, precedences, seed=1, time_limit_s=2.0)
        solve = time.perf_counter() - t0
        print(f"precedence: {n} stops, {len(precedences)} pairs; lists + cycle check ours {1e6 * ours:.0f} µs, "
              f"networkx {1e6 * theirs:.0f} µs (ratio {theirs / ours:.1f}); the whole solve_precedence "
              f"{1e3 * solve:.0f} ms (networkx would add {100 * (theirs - ours) / solve:.2f} %)")


# ---------------------------------------------------------------------------------------- 3. strategy graph
def strategy() -> None:
    from planners.ordering import solve_tsp

    for k in (4, 8, 12, 20):
        rng = random.Random(k)
        points = [(0.0, 0.0)] + [(rng.uniform(-500, 500), rng.uniform(-500, 500)) for _ in range(k)]

        def ours(points: list[tuple[float, float]] = points) -> float:
            return float(solve_tsp(points, start=0, closed=False, seed=0).cost)

        def theirs(points: list[tuple[float, float]] = points) -> float:
            graph = nx.complete_graph(len(points))
            for a, b in graph.edges:
                graph[a][b]["weight"] = math.dist(points[a], points[b])
            cycle = nx.approximation.christofides(graph)[:-1]
            i = cycle.index(0)  # the vehicle's position comes first: the cycle from there, less its return leg
            path = cycle[i:] + cycle[:i]
            return sum(math.dist(points[a], points[b]) for a, b in zip(path, path[1:], strict=False))

        t_ours, t_nx = best_of(ours, repeat=3), best_of(theirs, repeat=3)
        print(f"strategy: {k} objects; ours {1e3 * t_ours:.2f} ms, length {ours():.0f} m; networkx "
              f"{1e3 * t_nx:.2f} ms (ratio {t_nx / t_ours:.2f}), length {theirs():.0f} m "
              f"({100 * (theirs() / ours() - 1):+.1f} %)")


if __name__ == "__main__":
    routing()
    precedence()
    strategy()
