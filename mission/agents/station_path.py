"""Following a 3-D path by station keeping (seed 002 §2.2: a vehicle that can hover and move sideways).

The paths between next-best views are RRT paths in a voxel map that keep a safety distance; a cruising vehicle
with a 6 m turning circle would cut their corners. A hovering vehicle follows them closely instead: its station
is a carrot `lead` metres ahead of its projection on the path, so it moves along the path at the hover speed
whatever its heading (which stays free to point the scanner).

>>> p = StationPath([[0.0, 0.0, 10.0], [10.0, 0.0, 10.0], [10.0, 10.0, 12.0]], lead=1.0)
>>> p.carrot((0.2, 0.3, 10.0)).round(3).tolist()
[1.2, 0.0, 10.0]
>>> p.carrot((10.0, 5.0, 11.0)).round(3).tolist(), p.done
([10.0, 5.981, 11.196], False)
>>> p.carrot((10.0, 10.0, 12.0)).round(3).tolist(), p.done
([10.0, 10.0, 12.0], True)
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]


class StationPath:
    """A polyline (K, 3) in NED metres with monotone progress along it."""

    def __init__(self, points: ArrayLike, lead: float = 1.0, arrival: float = 0.4) -> None:
        self.points = np.asarray(points, dtype=float).reshape(-1, 3)
        seg = np.linalg.norm(np.diff(self.points, axis=0), axis=1)
        self.cumulative = np.concatenate([[0.0], np.cumsum(seg)])
        self.length = float(self.cumulative[-1])
        self.lead = float(lead)
        self.arrival = float(arrival)
        self.progress = 0.0
        self.done = len(self.points) < 2 or self.length == 0.0

    def at(self, s: float) -> Array:
        """The point at arc length `s` (clamped to the path)."""
        s = min(max(s, 0.0), self.length)
        if len(self.points) == 1:
            return np.array(self.points[0], dtype=np.float64)
        k = int(np.clip(np.searchsorted(self.cumulative, s, side="right") - 1, 0, len(self.points) - 2))
        span = self.cumulative[k + 1] - self.cumulative[k]
        t = (s - self.cumulative[k]) / span if span > 0 else 0.0
        return np.asarray(self.points[k] + t * (self.points[k + 1] - self.points[k]), dtype=float)

    def project(self, position: ArrayLike) -> float:
        """Arc length of the point of the path nearest `position`, not behind the progress made so far."""
        p = np.asarray(position, dtype=float).reshape(3)
        a, b = self.points[:-1], self.points[1:]
        d = b - a
        span = np.einsum("ij,ij->i", d, d)
        t = np.clip(np.einsum("ij,ij->i", p - a, d) / np.where(span > 0, span, 1.0), 0.0, 1.0)
        s = self.cumulative[:-1] + t * np.sqrt(span)
        dist = np.linalg.norm(a + t[:, None] * d - p, axis=1)
        ahead = s >= self.progress - 0.5
        if not ahead.any():
            return self.progress
        best = int(np.argmin(np.where(ahead, dist, np.inf)))
        return float(s[best])

    def carrot(self, position: ArrayLike) -> Array:
        """The station to hold now; sets `done` once the end is reached."""
        if self.done:
            return np.array(self.points[-1], dtype=np.float64)
        self.progress = max(self.progress, self.project(position))
        end = self.points[-1]
        if self.length - self.progress <= self.arrival and \
                float(np.linalg.norm(np.asarray(position, dtype=float) - end)) <= self.arrival:
            self.done = True
        return self.at(self.progress + self.lead)

    def remaining(self) -> Array:
        """The part of the path still ahead (from the current progress point)."""
        k = int(np.searchsorted(self.cumulative, self.progress, side="right"))
        return np.concatenate([self.at(self.progress)[None], self.points[k:]])
