"""What the executive and agents exchange with a vehicle: estimated state in, setpoints out.

The simulator is one implementation of `VehicleInterface`; a real vehicle is an adapter behind the same six calls
(adapters are entry points in the group `auv.vehicles`, picked by the scheme of a `--vehicle` URI). Nothing here
knows the truth.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from mission.plugin_api import StereoImages


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


@dataclass(frozen=True, eq=False)
class SonarPing:
    """One multibeam ping in the sensor frame, with the navigation estimate at the time it was taken.

    Beam k points at `angles_deg[k]` across track from the vehicle's down axis (positive to starboard) and
    returned at `ranges[k]` metres when `hit[k]`. The pose is the estimate: agents place pings with it.
    """

    time: float
    ranges: NDArray[np.float64]
    angles_deg: NDArray[np.float64]
    hit: NDArray[np.bool_]
    north: float
    east: float
    depth: float
    heading: float
    position_sigma: float


@dataclass(frozen=True, eq=False)
class ScanFrame:
    """One 3-D scanner frame (laser or structured light) with the navigation estimate at the time it was taken.

    Ray k points along `directions_body[k]` (unit vectors in the vehicle body frame: x forward, y starboard,
    z down; the scanner's mounting tilt included) and returned at `ranges[k]` metres when `hit[k]`; a ray with no
    return has range `max_range` (free out to there). The pose is the estimate (flat attitude: the vehicle holds
    zero pitch and roll): agents place frames with it.
    """

    time: float
    ranges: NDArray[np.float64]
    directions_body: NDArray[np.float64]
    hit: NDArray[np.bool_]
    max_range: float
    north: float
    east: float
    depth: float
    heading: float
    position_sigma: float


@dataclass(frozen=True)
class Observation:
    """Everything an agent may look at on one control tick: the estimate and the sensor products since the
    previous tick (empty when the payload is off)."""

    nav: NavState
    sonar: tuple[SonarPing, ...] = ()
    stereo: tuple[StereoImages, ...] = ()
    scans: tuple[ScanFrame, ...] = ()
    in_control: bool = True  # False while a pilot has taken the vehicle over: the executive pauses the mission


@dataclass(frozen=True)
class Command:
    """Autopilot setpoints: heading (deg), speed through water (m/s), and depth or altitude (m) or neither.

    `station` (north, east in the estimated frame) asks a hover-capable vehicle to hold that point: the
    autopilot then drives towards it at up to `STATION_KEEPING_SPEED_M_S` whatever the heading, and `speed` is
    ignored."""

    heading: float
    speed: float
    depth: float | None = None
    altitude: float | None = None
    station: tuple[float, float] | None = None

    @staticmethod
    def hold(nav: NavState) -> Command:
        """Stop and keep the current depth and heading."""
        return Command(heading=nav.heading, speed=0.0, depth=nav.depth)


STATION_KEEPING_SPEED_M_S = 0.3  # m/s: the fastest a station-keeping vehicle moves towards its station
HOVER_GAIN = 0.5  # (m/s) per metre of station error


class VehicleInterface(Protocol):
    """The executive's view of a vehicle (simulated or real). A real vehicle's adapter raises
    `mission.errors.LinkLostError` from `observe` or `advance` when its link has been silent too long."""

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

    def set_payload(self, sensors: frozenset[str]) -> None:
        """Switch the named payload sensors on (`mbes`, `stereo`, …) and every other one off."""
        ...

    def set_frame_rate(self, rate_hz: float | None) -> None:
        """Trigger the stereo camera at this rate (capped by the camera's own; None: the camera's own rate)."""
        ...

    def advance(self) -> None:
        """Let one control period pass (the simulator integrates it; a real vehicle waits for its own clock,
        never longer than a few periods of wall time)."""
        ...
