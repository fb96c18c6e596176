"""The recent navigation estimate, interpolated to a sensor frame's own stamp (never the latest estimate: a ping
taken 0.3 s ago is placed where the vehicle was 0.3 s ago)."""

from __future__ import annotations

import bisect
from collections import deque
from dataclasses import replace

from mission.vehicle import NavState

HISTORY_S = 60.0  # s of vehicle time kept


def _lerp_heading(a: float, b: float, w: float) -> float:
    """Heading between a and b (degrees), the short way round.

    >>> _lerp_heading(350.0, 10.0, 0.5)
    0.0
    """
    d = (b - a + 180.0) % 360.0 - 180.0
    return (a + w * d) % 360.0


class NavTrack:
    """Navigation estimates in time order (the vehicle's clock); `at(t)` interpolates between the two around t."""

    def __init__(self, history_s: float = HISTORY_S):
        self.history_s = history_s
        self._states: deque[NavState] = deque()
        self._times: deque[float] = deque()

    def add(self, nav: NavState) -> None:
        if self._times and nav.time <= self._times[-1]:
            if nav.time < self._times[-1] - 1.0:  # the vehicle's clock restarted (a reboot): start again
                self._states.clear()
                self._times.clear()
            else:
                return
        self._states.append(nav)
        self._times.append(nav.time)
        while self._times and self._times[0] < nav.time - self.history_s:
            self._states.popleft()
            self._times.popleft()

    @property
    def latest_time(self) -> float | None:
        return self._times[-1] if self._times else None

    def at(self, t: float) -> NavState | None:
        """The estimate at time t: interpolated inside the history, the oldest one before it, None after the
        newest (the estimate has not reached t yet: the frame waits)."""
        if not self._times or t > self._times[-1] + 1e-6:
            return None
        times = list(self._times)
        i = bisect.bisect_left(times, t)
        if i == 0:
            return self._states[0] if t >= times[0] - 1e-6 else replace(self._states[0], time=t)
        if i >= len(times):
            return self._states[-1]
        a, b = self._states[i - 1], self._states[i]
        w = (t - a.time) / (b.time - a.time)
        return replace(
            a, time=t, north=a.north + w * (b.north - a.north), east=a.east + w * (b.east - a.east),
            depth=a.depth + w * (b.depth - a.depth), heading=_lerp_heading(a.heading, b.heading, w),
            speed=a.speed + w * (b.speed - a.speed),
            position_sigma=a.position_sigma + w * (b.position_sigma - a.position_sigma))
