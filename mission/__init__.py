"""auv-mission: plan, simulate and execute AUV inspection missions over subsea production systems."""

from mission.errors import AuvError, MissionError
from mission.language import Mission, load_mission, validate_mission_file

__all__ = ["AuvError", "Mission", "MissionError", "load_mission", "simulate", "validate_mission_file"]


def simulate(mission: Mission, seed: int | None = None, **options: object) -> object:
    """Simulate a mission in its world (see `mission.sim.run.simulate`)."""
    from mission.sim.run import simulate as _simulate

    return _simulate(mission, seed=seed, **options)  # type: ignore[arg-type]
