"""Safe paths in the occupancy map with OMPL's RRT family (seed 002 §2.2.1: RRT with node evaluation favouring
informative areas; §2.2.2: a safe route from view to view).

`plan_path` sets up OMPL (`planners.rrt.spaces`) over a clearance grid (`planners.rrt.clearance`), optionally
with the information-weighted objective (`planners.rrt.information`), solves with a planner chosen by name,
then simplifies (OMPL's `PathSimplifier`: vertex reduction for plain length only, since it ignores cost; the
cost-aware partial shortcut; B-spline smoothing in R³), re-checking the whole path after each stage
(`PathGeometric.check`: every state, and every motion at the checking step) and falling back to the previous
stage when a check fails.

Safety: a state is valid when its voxel's clearance bound is at least `safety_distance + step/2`, and motions are
checked every `step` (a quarter voxel by default), so every point of an accepted motion keeps `safety_distance`
from every obstacle voxel.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from planners.rrt import _ompl
from planners.rrt.clearance import ClearanceGrid
from planners.rrt.information import InformationField, information_objective, path_cost, path_information
from planners.rrt.spaces import PlanningSpace, build_space, validity_checker

Array = NDArray[np.float64]
PLANNERS = ("RRT", "RRTConnect", "RRTstar", "InformedRRTstar", "BITstar")
"""Planner names `plan_path` accepts (OMPL's class names)."""


@dataclass(frozen=True)
class PathResult:
    """A planned path: waypoints (K, 3) in NED metres (for Dubins, samples along the curves ≤ one voxel apart)."""

    points: Array
    cost: float
    """The objective along the final path, integrated densely: its length for the plain objective, ∫ w(Î) ds
    (information-weighted metres, ≥ length) otherwise (OMPL's `motionCost` samples it every two map cells)."""
    length: float
    solved: bool
    """True when OMPL found an exact solution."""
    planner: str
    time: float
    """Seconds spent planning (solve only)."""
    headings_deg: Array = field(default_factory=lambda: np.zeros(0))
    """Heading at each point (Dubins only; empty otherwise)."""
    information: float = 0.0
    """∫ Î ds along the path when an information field was given."""
    smoothed: bool = False


@dataclass
class Problem:
    """An OMPL problem set up over a grid; kept so that benchmarks can run planners on the same setup."""

    setup: Any
    space: PlanningSpace
    objective: Any
    step: float
    required_clearance: float
    checker: Callable[[Any], bool]


def make_planner(name: str, si: Any) -> Any:
    """An OMPL geometric planner by class name (one of `PLANNERS`).

    RRT* and Informed RRT* use their r-disc neighbourhoods: with a Python objective, the k-nearest form of this
    build evaluated the motion cost to nearly every node at each iteration (calls grew with n², a tenth of the
    nodes in the same time).
    """
    _, geometric, _ = _ompl.load()
    if name not in PLANNERS:
        raise ValueError(f"unknown planner '{name}' (expected one of {', '.join(PLANNERS)})")
    planner = getattr(geometric, name)(si)
    if hasattr(planner, "setKNearest"):
        planner.setKNearest(False)
    return planner


def setup_problem(grid: ClearanceGrid, start: ArrayLike, goal: ArrayLike, *, safety_distance: float,
                  information: InformationField | None = None, discount: float = 0.8,
                  turning_radius: float | None = None, step: float | None = None) -> Problem:
    """An OMPL `SimpleSetup` for one start and goal (points (3,), or (4,) with a heading in degrees for Dubins)."""
    base, geometric, _ = _ompl.load()
    step = grid.cell / 4.0 if step is None else float(step)
    required = float(safety_distance) + step / 2.0
    space = build_space(grid, turning_radius)
    ss = geometric.SimpleSetup(space.space)
    checker = validity_checker(grid, required, space.dubins)
    ss.setStateValidityChecker(checker)
    si = ss.getSpaceInformation()
    si.setStateValidityCheckingResolution(step / space.space.getMaximumExtent())
    s = np.asarray(start, dtype=float).ravel()
    g = np.asarray(goal, dtype=float).ravel()
    chord = math.degrees(math.atan2(g[1] - s[1], g[0] - s[0]))
    start_state = space.make_state(s[:3], float(s[3]) if len(s) > 3 else chord)
    goal_state = space.make_state(g[:3], float(g[3]) if len(g) > 3 else chord)
    for name, st, p in (("start", start_state, s), ("goal", goal_state, g)):
        if not checker(st):
            raise ValueError(f"{name} {np.round(p[:3], 3).tolist()} is not {safety_distance:g} m clear of "
                             f"obstacles (clearance {float(grid.at(p[:3])[0]):.2f} m) or lies outside the grid")
    ss.setStartAndGoalStates(start_state, goal_state)
    if information is None and not space.dubins:
        objective = base.PathLengthOptimizationObjective(si)  # all in C++
    else:
        objective = information_objective(si, information, discount, space.xy_getter(),
                                          path_length_base=not space.dubins)
    ss.setOptimizationObjective(objective)
    return Problem(ss, space, objective, step, required, checker)


def plan_path(grid: ClearanceGrid, start: ArrayLike, goal: ArrayLike, *, safety_distance: float,
              planner: str = "RRTstar", time_limit_s: float = 1.0, information: InformationField | None = None,
              discount: float = 0.8, turning_radius: float | None = None, seed: int | None = None,
              iterations: int | None = None, simplify: bool = True, step: float | None = None) -> PathResult:
    """A collision-free path from `start` to `goal` keeping `safety_distance` from obstacle voxels.

    `planner` is an OMPL class name (`PLANNERS`); `information` switches to the information-weighted objective
    (`discount` α: a metre over the most informative cell costs 1 − α of a blank one); `turning_radius` plans in
    Dubins × depth instead of R³ (start/goal may carry a heading in degrees as a 4th value; otherwise both face
    along the start→goal chord). `iterations` stops after that many planner iterations (the time limit then only
    caps the run when positive; with `seed`, a repeatable run). Raises ValueError when the start or goal is unsafe.
    """
    _, geometric, _ = _ompl.load()
    problem = setup_problem(grid, start, goal, safety_distance=safety_distance, information=information,
                            discount=discount, turning_radius=turning_radius, step=step)
    _ompl.seed(seed)
    ss = problem.setup
    ss.setPlanner(make_planner(planner, ss.getSpaceInformation()))
    t0 = time.perf_counter()
    ss.solve(_termination(time_limit_s, iterations))
    elapsed = time.perf_counter() - t0
    solved = bool(ss.haveExactSolutionPath())
    if not ss.haveSolutionPath():
        return PathResult(np.zeros((0, 3)), math.inf, math.inf, False, planner, elapsed)
    path = geometric.PathGeometric(ss.getSolutionPath())
    smoothed = False
    if simplify and solved:
        path, smoothed = _simplify(problem, path, plain=information is None)
    points, headings = _points(problem, path)
    return PathResult(points, path_cost(points, information, discount), _length(points), solved, planner, elapsed,
                      headings, path_information(points, information) if information is not None else 0.0,
                      smoothed)


def _termination(time_limit_s: float, iterations: int | None) -> Any:
    """OMPL's timed condition, or an iteration count (capped by the time limit when that is positive)."""
    base, _, _ = _ompl.load()
    if iterations is None:
        return base.timedPlannerTerminationCondition(float(time_limit_s))
    count = [0]
    deadline = time.perf_counter() + float(time_limit_s) if time_limit_s > 0 else math.inf

    def done() -> bool:
        count[0] += 1
        return count[0] > iterations or time.perf_counter() > deadline

    return base.PlannerTerminationCondition(done)


def _simplify(problem: Problem, path: Any, plain: bool) -> tuple[Any, bool]:
    """Shorten (cost-aware), then smooth in R³; each stage is kept only if the whole path re-checks valid.

    The re-check matters: the partial shortcut splits motions at interpolated states, and the discrete check of
    a piece of a valid motion samples other points than the check of the whole did.
    """
    _, geometric, _ = _ompl.load()
    si = problem.setup.getSpaceInformation()
    goal = problem.setup.getProblemDefinition().getGoal()
    simplifier = geometric.PathSimplifier(si, goal, problem.objective)
    short = geometric.PathGeometric(path)
    if plain:
        simplifier.reduceVertices(short)  # validity-only vertex removal: right for length, wrong for information
    simplifier.partialShortcutPath(short)  # accepts a shortcut only when the objective's cost drops
    if _densely_valid(short):
        path = short
    if problem.space.dubins:
        return path, False  # Dubins segments are already curvature-bounded; a B-spline would break the bound
    smooth = geometric.PathGeometric(path)
    simplifier.smoothBSpline(smooth, 3)
    before = path.cost(problem.objective).value()
    after = smooth.cost(problem.objective).value()
    if _densely_valid(smooth) and after <= before * 1.01:
        return smooth, True
    return path, False


def _densely_valid(path: Any) -> bool:
    """Every state and every motion of the path passes OMPL's checks (motions sampled at the checking step)."""
    return bool(path.check())


def _points(problem: Problem, path: Any) -> tuple[Array, Array]:
    _, geometric, _ = _ompl.load()
    space = problem.space
    if space.dubins:
        dense = geometric.PathGeometric(path)
        cell = problem.step * 4.0
        dense.interpolate(max(2, math.ceil(dense.length() / cell) + 1))
        path = dense
    states = [path.getState(i) for i in range(path.getStateCount())]
    points = np.array([space.xyz(s) for s in states], dtype=float).reshape(-1, 3)
    headings = np.array([space.heading_deg(s) for s in states]) if space.dubins else np.zeros(0)
    return points, headings


def _length(points: Array) -> float:
    return float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum()) if len(points) > 1 else 0.0
