"""Safety monitors of the strategic level: geofence, maximum depth, minimum altitude, mission duration and
energy reserve, checked on the navigation estimate every tick. Each monitor reports a violation once.
"""

from __future__ import annotations

from dataclasses import dataclass

import shapely
from shapely.geometry import Polygon

from mission.language.models import Safety
from mission.vehicle import NavState

SURFACE_DEPTH = 1.0  # m: above this depth the altitude limit does not apply (launch and recovery)


@dataclass(frozen=True)
class Violation:
    monitor: str
    message: str


class SafetyMonitors:
    """All monitors of a mission's `safety:` block; `check` returns the violations new at this tick."""

    def __init__(self, safety: Safety, energy_capacity_wh: float, start_time: float = 0.0):
        self.safety = safety
        self.capacity = energy_capacity_wh
        self.start_time = start_time
        self.fence: Polygon | None = None
        if safety.geofence is not None:
            self.fence = Polygon([(e, n) for n, e in safety.geofence])
            shapely.prepare(self.fence)
        self.tripped: set[str] = set()

    def _current(self, nav: NavState) -> list[Violation]:
        s = self.safety
        found = []
        if self.fence is not None and not shapely.contains_xy(self.fence, nav.east, nav.north):
            found.append(Violation("geofence", f"left the geofence at ({nav.north:.1f}, {nav.east:.1f})"))
        if nav.depth > s.max_depth:
            found.append(Violation("max_depth", f"depth {nav.depth:.1f} m beyond max_depth {s.max_depth:g} m"))
        if nav.altitude is not None and nav.depth > SURFACE_DEPTH and nav.altitude < s.min_altitude:
            found.append(Violation("min_altitude",
                                   f"altitude {nav.altitude:.2f} m below min_altitude {s.min_altitude:g} m"))
        elapsed = nav.time - self.start_time
        if elapsed > s.max_duration:
            found.append(Violation("max_duration", f"mission time {elapsed:.0f} s beyond max_duration "
                                                   f"{s.max_duration:.0f} s"))
        reserve = s.energy_reserve / 100.0 * self.capacity
        if nav.energy_wh < reserve:
            found.append(Violation("energy_reserve", f"energy {nav.energy_wh:.0f} Wh below the reserve "
                                                     f"{reserve:.0f} Wh ({s.energy_reserve:g}%)"))
        return found

    def check(self, nav: NavState) -> list[Violation]:
        """Violations that appeared at this tick (each monitor trips once)."""
        new = [v for v in self._current(nav) if v.monitor not in self.tripped]
        self.tripped.update(v.monitor for v in new)
        return new
