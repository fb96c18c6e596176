"""Line-of-sight path following (Fossen's LOS guidance): the heading that converges onto a straight leg.

>>> round(los_heading((0.0, 0.0), (100.0, 0.0), (50.0, 0.0), lookahead=10.0), 3)
0.0
>>> round(los_heading((0.0, 0.0), (100.0, 0.0), (50.0, -10.0), lookahead=10.0), 3)
45.0
"""

from __future__ import annotations

import math


def leg_progress(start: tuple[float, float], end: tuple[float, float], pos: tuple[float, float]
                 ) -> tuple[float, float, float]:
    """(along-track distance, signed cross-track error (+ starboard of the leg), leg length)."""
    dn, de = end[0] - start[0], end[1] - start[1]
    length = math.hypot(dn, de)
    if length < 1e-9:
        return 0.0, 0.0, 0.0
    pn, pe = pos[0] - start[0], pos[1] - start[1]
    along = (pn * dn + pe * de) / length
    cross = (-pn * de + pe * dn) / length
    return along, cross, length


def los_heading(start: tuple[float, float], end: tuple[float, float], pos: tuple[float, float],
                lookahead: float) -> float:
    """Heading (deg) that steers from `pos` onto the leg start→end with the given look-ahead distance."""
    _, cross, length = leg_progress(start, end, pos)
    if length < 1e-9:
        return math.degrees(math.atan2(end[1] - pos[1], end[0] - pos[0])) % 360.0
    path_angle = math.atan2(end[1] - start[1], end[0] - start[0])
    return math.degrees(path_angle - math.atan2(cross, lookahead)) % 360.0
