"""Following a polyline of waypoints by line-of-sight guidance, leg after leg (used by agents whose plans are
paths: survey meanders, photo passes)."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from mission.guidance import leg_progress, los_heading


class PathFollower:
    """Steers along `waypoints` ((K, 2) north, east) from the vehicle's position when it starts."""

    def __init__(self, start: tuple[float, float], waypoints: NDArray[np.float64], lookahead: float, acceptance: float):
        self.points = [start] + [(float(n), float(e)) for n, e in waypoints]
        self.leg = 0
        self.lookahead = lookahead
        self.acceptance = acceptance

    @property
    def done(self) -> bool:
        return self.leg >= len(self.points) - 1

    def heading(self, north: float, east: float) -> float:
        """Heading to steer now; advances past legs whose end has been reached or passed."""
        pos = (north, east)
        while not self.done:
            a, b = self.points[self.leg], self.points[self.leg + 1]
            along, _, length = leg_progress(a, b, pos)
            if math.hypot(b[0] - north, b[1] - east) <= self.acceptance or along >= length:
                self.leg += 1
                continue
            return los_heading(a, b, pos, self.lookahead)
        last = self.points[-1]
        return math.degrees(math.atan2(last[1] - east, last[0] - north)) % 360.0

    def remaining_path(self) -> list[tuple[float, float]]:
        return self.points[self.leg + 1:]
