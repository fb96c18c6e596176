"""The result of coverage planning (seed 002 §2.1: the array of survey lines and the path through them) and its
assembly from runs joined by transits.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from .frames import ne
from .runs import Run
from .scene import Scene

Array = NDArray[np.float64]


@dataclass(frozen=True)
class CoveragePlan:
    """A coverage path. Coordinates are [north, east] metres; headings degrees clockwise from north.

    `waypoints` is the whole path, turns and transits included (arcs sampled every 10°); `lines` are the survey
    passes in flying order (the meander lines, then any contour passes round zones, as flown); `turns` counts
    the manoeuvres between passes (turns inside cells plus transits); `length_m` is the length of `waypoints`.
    """

    waypoints: Array
    lines: list[Array] = field(repr=False)
    heading_deg: float
    spacing: float
    turns: int
    length_m: float
    cells: int
    method: str


def estimated_length(scene: Scene, runs: Sequence[Run]) -> float:
    """Length of `runs` flown in order, with the transits estimated (`Scene.pair_costs`) rather than built."""
    inner = sum(r.length for r in runs)
    if len(runs) < 2:
        return inner
    hops = scene.pair_costs(np.array([r.path[-1] for r in runs[:-1]]), np.array([r.exit_angle for r in runs[:-1]]),
                            np.array([r.path[0] for r in runs[1:]]), np.array([r.entry_angle for r in runs[1:]]))
    return inner + float(hops.sum())


def count_turns(runs: Sequence[Run]) -> int:
    """Manoeuvres between passes: the turns inside runs plus one per transit."""
    return sum(r.turns for r in runs) + len(runs) - 1


def assemble(scene: Scene, runs: Sequence[Run], heading_deg: float, spacing: float, cells: int,
             method: str) -> CoveragePlan:
    """Fly `runs` in order, joined by transits that keep out of the zones."""
    parts = [runs[0].path]
    lines = list(runs[0].lines)
    turns = runs[0].turns
    for a, b in zip(runs[:-1], runs[1:], strict=True):
        hop = scene.transit(a.path[-1], a.exit_angle, b.path[0], b.entry_angle)
        parts.extend([hop[1:], b.path[1:]])
        lines.extend(b.lines)
        turns += 1 + b.turns
    path = np.concatenate(parts)
    step = np.linalg.norm(np.diff(path, axis=0), axis=1)
    path = np.concatenate([path[:1], path[1:][step > 1e-9]])
    length = float(np.linalg.norm(np.diff(path, axis=0), axis=1).sum())
    return CoveragePlan(ne(path), [ne(seg) for seg in lines], float(heading_deg % 180.0), float(spacing), turns,
                        length, cells, method)
