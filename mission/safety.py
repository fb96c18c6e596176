"""Safety monitors of the strategic level: geofence, maximum depth, minimum altitude, mission duration and
energy reserve, checked on the navigation estimate every tick. Each monitor reports a violation once. And what
the mission's `on_violation` policy makes of a violation: the abort legs.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal

import shapely
from shapely.geometry import Polygon

from mission.language.models import Mission, Safety, Transit
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


def policy_record(mission: Mission) -> dict[str, Any]:
    """The mission's `on_violation` policy as an event field."""
    policy = mission.safety.on_violation
    to = policy.abort_to if isinstance(policy.abort_to, str) else policy.abort_to.model_dump()
    return {"abort_to": to, "surface": policy.surface}


def abort_legs(mission: Mission, nav: NavState, usbl: bool) -> list[tuple[str, Transit]]:
    """The transits of an abort (per `safety.on_violation`): to the abort point at a safe depth (no deeper than
    now, 10 % above the depth limit, and 2 m above the altitude floor), then, if the policy says so, to the
    surface (or the abort point's depth) there."""
    policy = mission.safety.on_violation
    to: Any
    if isinstance(policy.abort_to, str):
        to, final_depth = "home", mission.home.depth
    else:
        to, final_depth = {"north": policy.abort_to.north, "east": policy.abort_to.east}, policy.abort_to.depth
    safe_depth = min(nav.depth, 0.9 * mission.safety.max_depth)
    floor = mission.safety.min_altitude + 2.0
    if nav.altitude is not None and nav.altitude < floor:
        safe_depth = max(0.0, safe_depth - (floor - nav.altitude))
    navigation: Literal["usbl", "dead-reckoning"] = "usbl" if usbl else "dead-reckoning"
    legs = [("abort-return", Transit(to=to, depth=safe_depth, navigation=navigation))]
    if policy.surface:
        legs.append(("abort-surface", Transit(to=to, depth=final_depth, navigation=navigation)))
    return legs
