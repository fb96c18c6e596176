"""auv-mission: plan, simulate and execute AUV inspection missions over subsea production systems.

The names below load on first use, so that `import mission.plugin_api` or `import mission.geometry` (the plug-in
API) does not pull in the mission language and its dependencies.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from mission.errors import AuvError, MissionError
    from mission.language import Mission, load_mission, validate_mission_file
    from mission.sim.run import RunResult

__all__ = ["AuvError", "Mission", "MissionError", "load_mission", "simulate", "validate_mission_file"]

_LAZY = {"AuvError": "mission.errors", "MissionError": "mission.errors", "Mission": "mission.language",
         "load_mission": "mission.language", "validate_mission_file": "mission.language"}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'mission' has no attribute {name!r}")


def simulate(mission: Mission, seed: int | None = None, **options: Any) -> RunResult:
    """Simulate a mission in its world (see `mission.sim.run.simulate`)."""
    from mission.sim.run import simulate as _simulate

    return _simulate(mission, seed=seed, **options)
