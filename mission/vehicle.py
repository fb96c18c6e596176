"""What the executive and agents exchange with a vehicle: estimated state in, setpoints out.

The simulator is one implementation of `Vehicle`; a real vehicle is an adapter behind the same four calls.
Nothing here knows the truth.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol


@dataclass(frozen=True)
class NavState:
    """The navigation estimate (NED metres, degrees, seconds), as the vehicle's filter gives it."""

    time: float
    north: float
    east: float
    depth: float
    heading: float
    speed: float
    altitude: float | None
    position_sigma: float
    energy_wh: float


@dataclass(frozen=True)
class Observation:
    """Everything an agent may look at on one control tick."""

    nav: NavState


@dataclass(frozen=True)
class Command:
    """Autopilot setpoints: heading (deg), speed through water (m/s), and depth or altitude (m) or neither."""

    heading: float
    speed: float
    depth: float | None = None
    altitude: float | None = None

    @staticmethod
    def hold(nav: NavState) -> Command:
        """Stop and keep the current depth and heading."""
        return Command(heading=nav.heading, speed=0.0, depth=nav.depth)


class Vehicle(Protocol):
    """The executive's view of a vehicle (simulated or real)."""

    control_period: float

    def observe(self) -> Observation:
        """The current estimate and sensor products."""
        ...

    def apply(self, command: Command) -> None:
        """Hand setpoints to the autopilot."""
        ...

    def set_aiding(self, usbl: bool) -> None:
        """Use (or ignore) acoustic position fixes in the navigation filter."""
        ...

    def advance(self) -> None:
        """Let one control period pass (the simulator integrates it; a real vehicle waits)."""
        ...
