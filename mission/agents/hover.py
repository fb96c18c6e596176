"""Getting a hover-capable vehicle to a pose: cruise towards it when far, station-keep when near, and say when
it is there (position, depth and heading within tolerance). Shared by the agents that work over objects."""

from __future__ import annotations

import math
from dataclasses import dataclass

from mission.frames import wrap_deg
from mission.vehicle import Command, NavState

STATION_M = 4.0  # within this distance the vehicle station-keeps instead of cruising
WORK_SPEED_M_S = 1.0  # the top speed through the water from view to view over an object (the cruise speed if lower)
DEPTH_TOLERANCE_M = 0.3
HEADING_TOLERANCE_DEG = 3.0


@dataclass(frozen=True)
class Goal:
    """A hover pose in the estimated frame (NED metres, heading in degrees)."""

    north: float
    east: float
    depth: float
    heading: float


def hover_command(nav: NavState, goal: Goal, speed: float, tolerance: float = 0.3,
                  depth_tolerance: float = DEPTH_TOLERANCE_M, station_m: float = STATION_M
                  ) -> tuple[Command, bool]:
    """The command that brings the vehicle to `goal`, and whether it is there now: cruising towards it beyond
    `station_m`, station-keeping (any direction, slowly) within.

    >>> nav = NavState(0, 0.0, 0.0, 10.0, 90.0, 0.0, 5.0, 0.1, 100.0)
    >>> hover_command(nav, Goal(10.0, 0.0, 10.0, 90.0), 1.0)[0].heading
    0.0
    >>> hover_command(nav, Goal(0.1, 0.0, 10.1, 91.0), 1.0)
    (Command(heading=91.0, speed=0.0, depth=10.1, altitude=None, station=(0.1, 0.0)), True)
    """
    distance = math.hypot(goal.north - nav.north, goal.east - nav.east)
    aligned = abs(wrap_deg(nav.heading - goal.heading)) <= HEADING_TOLERANCE_DEG
    there = distance <= tolerance and abs(nav.depth - goal.depth) <= depth_tolerance and aligned
    if distance > station_m:
        heading = math.degrees(math.atan2(goal.east - nav.east, goal.north - nav.north)) % 360.0
        return Command(heading, min(speed, max(0.3, 0.2 * distance)), depth=goal.depth), False
    return Command(goal.heading, 0.0, depth=goal.depth, station=(goal.north, goal.east)), there
