"""Lazy import of OMPL (the `ompl` 2.x wheel, nanobind bindings) with an install hint; seeding and quiet logs.

OMPL is the sampling-based planning library seed 002 §2.2.1 names for RRT. It is imported only when a plan is
made, so that the rest of `planners` imports without it.
"""

from __future__ import annotations

from types import ModuleType
from typing import Any


def load() -> tuple[Any, Any, Any]:
    """`(ompl.base, ompl.geometric, ompl.util)`, logging errors only.

    OMPL logs at INFO by default; its expected warnings here (no cost-to-go heuristic for Dubins × depth, which
    is not a metric space) would only be noise.
    """
    try:
        from ompl import base, geometric, util
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError("planners.rrt needs OMPL's Python bindings: pip install 'ompl>=2'") from exc
    util.setLogLevel(util.LogLevel.LOG_ERROR)
    return base, geometric, util


def seed(value: int | None) -> None:
    """Seed OMPL's generator of per-planner seeds, so that a run is repeatable in a fresh state.

    OMPL complains (at error level) when seeding after random numbers were drawn, but re-seeds all the same;
    the complaint is silenced here.
    """
    if value is None:
        return
    _, _, util = load()
    level = util.getLogLevel()
    util.setLogLevel(util.LogLevel.LOG_NONE)
    util.RNG.setSeed(int(value) + 1)  # OMPL treats seed 0 as "pick one"
    util.setLogLevel(level)


def module(name: str) -> ModuleType:
    """One OMPL submodule by name (`base`, `geometric`, `util`, `tools`)."""
    import importlib

    load()
    return importlib.import_module(f"ompl.{name}")
