"""A run: one stretch of the survey flown without a transit (a cell's meander, a single line, or a contour pass
round a no-go zone), with the survey passes it contains (seed 002 §2.1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Run:
    path: Array                     # (K, 2) x, y: the passes and the turns between them, in flying order
    lines: tuple[Array, ...]        # survey passes, each (2, 2) x, y in flying order
    entry_angle: float              # math angles (radians) of travel at the first and last point
    exit_angle: float
    turns: int = 0                  # turns inside the run

    @property
    def length(self) -> float:
        return float(np.linalg.norm(np.diff(self.path, axis=0), axis=1).sum())

    def reversed(self) -> Run:
        """The same run flown the other way."""
        return Run(self.path[::-1].copy(), tuple(seg[::-1].copy() for seg in reversed(self.lines)),
                   self.exit_angle + math.pi, self.entry_angle + math.pi, self.turns)


def polyline_run(points: Array) -> Run:
    """A run along a polyline whose every segment is a survey pass (a contour pass).

    >>> run = polyline_run(np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 5.0]]))
    >>> len(run.lines), run.length, round(run.exit_angle, 4)
    (2, 15.0, 1.5708)
    """
    d0 = points[1] - points[0]
    d1 = points[-1] - points[-2]
    lines = tuple(points[k : k + 2].copy() for k in range(len(points) - 1))
    return Run(points, lines, math.atan2(d0[1], d0[0]), math.atan2(d1[1], d1[0]), 0)
