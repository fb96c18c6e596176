"""Hovering over an object without sweeping low over it: climb in place to a clearance depth, cross at it, and
descend only over the goal; and never deeper than the altimeter allows (something under the vehicle may stand
higher than the database says)."""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np

from mission.agents.hover import Goal, hover_command
from mission.agents.inspect.placement import Placement
from mission.agents.inspect.settings import InspectSettings
from mission.geometry import transform_points
from mission.vehicle import Command, NavState


class Mover:
    """Commands towards hover goals over an object whose known points (object frame) are `points`."""

    def __init__(self, place: Placement, points: Iterable[np.ndarray], min_altitude: float, speed: float,
                 settings: InspectSettings):
        self.place = place
        self.points = np.vstack(list(points))
        self.min_altitude = min_altitude
        self.speed = speed
        self.settings = settings

    def clearance_depth(self) -> float:
        """Moving across the object, stay this shallow: its highest known point plus the minimum altitude and a
        margin."""
        top = float(transform_points(self.place.T_wo, self.points)[:, 2].min())
        return top - self.min_altitude - self.settings.clearance_margin_m

    def altitude_floor(self, nav: NavState) -> float:
        """The deepest the vehicle may go here by its altimeter: the minimum altitude plus a margin."""
        if nav.altitude is None:
            return math.inf
        return nav.depth + nav.altitude - self.min_altitude - self.settings.altitude_margin_m

    def go(self, nav: NavState, goal: Goal, tolerance: float = 0.3, depth_tolerance: float = 0.3
           ) -> tuple[Command, bool]:
        """The command towards `goal`, and whether the vehicle is there (within the tolerances)."""
        s = self.settings
        floor = self.altitude_floor(nav)
        if floor < goal.depth:  # whatever lies under the vehicle is higher than the plan assumed: keep clear
            goal = Goal(goal.north, goal.east, floor, goal.heading)
        if math.hypot(goal.north - nav.north, goal.east - nav.east) > s.over_goal_m:
            depth = min(goal.depth, self.clearance_depth())
            if nav.depth > depth + 0.3:
                return Command(nav.heading, 0.0, depth=depth, station=(nav.north, nav.east)), False
            return hover_command(nav, Goal(goal.north, goal.east, depth, goal.heading), self.speed,
                                 station_m=s.station_radius_m)[0], False
        return hover_command(nav, goal, self.speed, tolerance, depth_tolerance, s.station_radius_m)
