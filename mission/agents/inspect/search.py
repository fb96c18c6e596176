"""The search pattern of the inspect agent (seed 002 §3.4: search motions until a point set is recognised): offsets
of an expanding square or a small meander around a set, and the order in which the sets' patterns are flown."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np


def expanding_square(step: float, count: int) -> list[tuple[float, float]]:
    """North/east offsets of an expanding-square search: legs of 1, 1, 2, 2, 3, … steps turning clockwise.

    >>> expanding_square(1.0, 6)
    [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (2.0, -1.0)]
    """
    out = [(0.0, 0.0)]
    n = e = 0.0
    directions = ((1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0))
    leg = 0
    while len(out) < count:
        dn, de = directions[leg % 4]
        length = leg // 2 + 1
        n, e = n + dn * length * step, e + de * length * step
        out.append((n, e))
        leg += 1
    return out


def meander_offsets(step: float, count: int) -> list[tuple[float, float]]:
    """North/east offsets of a small meander centred on the origin (rows `step` apart, east–west passes).

    >>> meander_offsets(1.0, 5)
    [(0.0, 0.0), (-1.0, -1.0), (-1.0, 0.0), (-1.0, 1.0), (0.0, 1.0)]
    """
    side = max(3, math.ceil(math.sqrt(max(count - 1, 1))) | 1)
    half = side // 2
    out = [(0.0, 0.0)]
    for i, row in enumerate(range(-half, half + 1)):
        cols = range(-half, half + 1) if i % 2 == 0 else range(half, -half - 1, -1)
        out.extend((row * step, col * step) for col in cols if (row, col) != (0, 0))
    return out[:count]


def pattern_offsets(pattern: str, step: float, count: int) -> list[tuple[float, float]]:
    """The mission's search pattern (`expanding-square` or `meander`) as `count` north/east offsets."""
    return expanding_square(step, count) if pattern == "expanding-square" else meander_offsets(step, count)


def search_order(sets: Mapping[str, np.ndarray]) -> list[str]:
    """The sets whose patterns are flown, most distinctive first: more points, then more relief.

    Flying one set's pattern leg by leg, the frames taken on the way sweep the ground between its positions;
    alternating sets position by position, they did not (measured: with the database 2.3 m off, no view of 131
    had the whole module top in it).

    >>> search_order({"a": np.zeros((4, 3)), "b": np.array([[0, 0, 0], [1, 0, 0.5], [0, 1, 0], [1, 1, 0.0]])})
    ['b', 'a']
    """
    return sorted(sets, key=lambda s: (-len(sets[s]), -float(np.ptp(sets[s][:, 2])), s))
