"""The `transit` agent: go to a point (or home) at a depth or an altitude, by line-of-sight guidance along the
straight leg from where the element started (seed 002 §1, route elements of the "move" kind).
"""

from __future__ import annotations

import math

from mission.agents.base import Agent, AgentContext
from mission.guidance import leg_progress, los_heading
from mission.language.models import Transit
from mission.vehicle import Command, Observation

DEPTH_TOLERANCE = 1.0  # m: a vertical target counts as reached within this band


class TransitAgent(Agent):
    kind = "transit"

    def __init__(self, params: Transit | None = None) -> None:
        super().__init__()
        self.params = params

    def start(self, context: AgentContext) -> None:
        p = self.params or context.element.transit
        assert p is not None
        self.params = p
        mission, nav = context.mission, context.nav
        if isinstance(p.to, str):
            self.target = (mission.home.north, mission.home.east)
        else:
            self.target = (p.to.north, p.to.east)
        self.origin = (nav.north, nav.east)
        self.speed = p.speed or mission.vehicle.cruise_speed
        self.navigation = p.navigation
        self.depth = p.depth if p.depth is not None or p.altitude is not None else nav.depth
        self.altitude = p.altitude
        # Look far enough ahead that the turning circle can follow the leg without oscillating.
        self.lookahead = max(2.0 * mission.vehicle.turn_radius, 8.0)
        self.capture = p.capture_radius

    def planned_path(self) -> list[tuple[float, float]]:
        return [self.origin, self.target]

    def _vertical_done(self, obs: Observation) -> bool:
        nav = obs.nav
        if self.altitude is not None:
            return nav.altitude is not None and abs(nav.altitude - self.altitude) <= DEPTH_TOLERANCE
        assert self.depth is not None
        return abs(nav.depth - self.depth) <= DEPTH_TOLERANCE

    def step(self, observation: Observation) -> Command:
        nav = observation.nav
        pos = (nav.north, nav.east)
        _, _, length = leg_progress(self.origin, self.target, pos)
        remaining = math.hypot(self.target[0] - nav.north, self.target[1] - nav.east)
        # Arrive with margin for the navigation uncertainty, so that the true position is inside the circle.
        threshold = max(self.capture - 3.0 * nav.position_sigma, 0.25 * self.capture)
        arrived = remaining <= threshold
        if arrived:
            if self._vertical_done(observation):
                self.succeed()
            return Command(nav.heading, 0.0, self.depth if self.altitude is None else None, self.altitude)
        if remaining <= self.lookahead or length < 1e-6:
            heading = math.degrees(math.atan2(self.target[1] - nav.east, self.target[0] - nav.north)) % 360.0
        else:
            heading = los_heading(self.origin, self.target, pos, self.lookahead)
        # Slow down on the final approach so that the turning circle does not orbit the capture circle.
        speed = self.speed if remaining > 3 * self.capture else max(0.3, self.speed * remaining / (3 * self.capture))
        return Command(heading, speed, self.depth if self.altitude is None else None, self.altitude)
