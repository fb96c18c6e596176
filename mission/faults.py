"""Faults a mission injects (`faults:`, `mission.language.models.Fault`) are for simulation only: the simulated
vehicle applies them (`mission.sim.faults`); a real vehicle cannot, so `auv run` refuses such a mission with a
line that points at the `faults:` key."""

from __future__ import annotations

from pathlib import Path

from mission.errors import Diagnostic
from mission.language.models import Mission


def faults_diagnostic(mission: Mission, why: str) -> Diagnostic:
    """A located error for the mission's `faults:` section (`why`: what refuses them)."""
    message = f"faults: inject faults in simulation only ({why}); remove the section to fly this mission"
    if mission.source is None or not Path(mission.source).is_file():
        return Diagnostic(mission.source or "<mission>", 1, 1, message)
    from mission.language.source import read_yaml

    doc = read_yaml(Path(mission.source))
    return doc.diagnostic(("faults",), message, key=True)
