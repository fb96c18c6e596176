"""Feasible viewpoints for target photographs (seed 002 §3.4; §2.2: side surfaces need oriented cameras and lateral
moves). A target's designed viewpoint puts the camera `standoff` metres from it along the optical axis, the vehicle
at its designed heading: straight above it with the default down-looking mount. The vehicle may not come closer
than its altitude floor (the mission's minimum altitude plus the agent's margin) to anything it knows under it: the
database's points and what its altimeter has measured. When the designed viewpoint breaks the floor, the nearest
feasible one is planned:

1. **raised**: along the same line of sight, as far back as the floor needs, when the target still fits the
   image there (the range at most `max_range_ratio` times the standoff: its detail at least that much of the
   design's);
2. else **oblique**: at the standoff range, the vehicle moved round the target (offset laterally, headed so the
   tilted camera looks at it), at the heading nearest the designed one whose viewpoint clears the floor and whose
   line of sight passes above every known point (a down-looking mount has no oblique view: it stays raised).

Everything is in world coordinates (NED, metres; headings in degrees clockwise from north), so that "under" and
"altitude" follow the world's vertical; the caller converts to and from the object frame.

>>> import numpy as np
>>> plan = plan_viewpoint(np.array([0.0, 0.0, 10.0]), 2.0, np.array([[0.0, 0.5, 9.5]]), 1.7, 0.0, 90.0)
>>> plan.kind, plan.camera.round(3).tolist(), round(plan.clearance_m, 3)  # 0.2 m higher over the 0.5 m high point
('raised', [0.0, 0.0, 7.8], 1.7)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mission.language.viewpoints import FOOTPRINT_M  # the planning-time check's footprint: one definition

Array = NDArray[np.float64]

SIGHT_RADIUS_M = 0.3  # a known point this close (horizontally) under the line of sight may block it
HEADING_STEP_DEG = 5.0  # oblique viewpoints are tried round the target at this step


@dataclass(frozen=True)
class Viewpoint:
    """A planned viewpoint: the left camera's position (world), the vehicle's heading, the range to the target,
    which rule gave it (`designed`, `raised`, `oblique`), its clearance over the highest known point under it,
    and whether it keeps the floor."""

    camera: Array
    heading_deg: float
    range_m: float
    kind: str
    clearance_m: float
    feasible: bool


def optical_axis(heading_deg: float, tilt_deg: float) -> Array:
    """The optical axis (world, unit) of a camera tilted `tilt_deg` down from the vehicle's forward direction.

    >>> optical_axis(90.0, 90.0).round(6).tolist(), optical_axis(90.0, 0.0).round(6).tolist()
    ([0.0, 0.0, 1.0], [0.0, 1.0, 0.0])
    """
    if tilt_deg == 90.0:
        return np.array([0.0, 0.0, 1.0])
    h, t = math.radians(heading_deg), math.radians(tilt_deg)
    return np.array([math.cos(t) * math.cos(h), math.cos(t) * math.sin(h), math.sin(t)])


def clearance(position: Array, known: Array, footprint_m: float = FOOTPRINT_M) -> float:
    """Height of `position` above the highest known point within `footprint_m` horizontally (inf: none there).

    >>> clearance(np.array([0.0, 0.0, 5.0]), np.array([[0.5, 0.0, 7.0], [3.0, 0.0, 6.0]]))
    2.0
    """
    if len(known) == 0:
        return math.inf
    near = np.hypot(known[:, 0] - position[0], known[:, 1] - position[1]) <= footprint_m
    return float(known[near, 2].min() - position[2]) if near.any() else math.inf


def sight_clear(camera: Array, target: Array, known: Array, radius_m: float = SIGHT_RADIUS_M) -> bool:
    """Whether the line from `camera` to `target` passes above every known point near it (points within
    `radius_m` of the target itself are the target's own surroundings and do not block).

    >>> sight_clear(np.array([0.0, 0.0, 0.0]), np.array([4.0, 0.0, 4.0]), np.array([[2.0, 0.0, 1.0]]))
    False
    """
    ray = target - camera
    length = float(np.hypot(ray[0], ray[1]))
    for p in known:
        if np.linalg.norm(p[:2] - target[:2]) <= radius_m:
            continue
        if length < 1e-9:
            continue
        s = float(np.clip(((p[:2] - camera[:2]) @ ray[:2]) / length**2, 0.0, 1.0))
        if np.linalg.norm(camera[:2] + s * ray[:2] - p[:2]) <= radius_m and p[2] < camera[2] + s * ray[2]:
            return False
    return True


def plan_viewpoint(target: Array, standoff: float, known: Array, floor_m: float, heading_deg: float,
                   tilt_deg: float, max_range_ratio: float = 1.25) -> Viewpoint:
    """The nearest feasible viewpoint of the target at `target` (world) from the designed one (`standoff` along
    the optical axis of a camera tilted `tilt_deg`, the vehicle at `heading_deg`), keeping `floor_m` above every
    `known` point (world, N×3) under it; see the module docstring for the rules. When no rule gives a feasible
    one, the viewpoint raised as far as the floor needs (beyond the ratio), or, when raising cannot clear it, the
    raised one at the ratio with `feasible` False."""
    need = floor_m

    def at(heading: float, rng: float, kind: str) -> Viewpoint:
        camera = target - rng * optical_axis(heading, tilt_deg)
        gap = clearance(camera, known)
        ok = gap >= need - 1e-9 and sight_clear(camera, target, known)
        return Viewpoint(camera, heading % 360.0, rng, kind, gap, ok)

    designed = at(heading_deg, standoff, "designed")
    if designed.feasible:
        return designed
    axis = optical_axis(heading_deg, tilt_deg)
    raised = _raise(target, standoff, known, need, axis)
    rng = raised if raised is not None else standoff * max_range_ratio
    if raised is not None and raised <= standoff * max_range_ratio + 1e-9:
        candidate = at(heading_deg, raised, "raised")
        if candidate.feasible:
            return candidate
    if tilt_deg < 90.0:
        steps = int(round(180.0 / HEADING_STEP_DEG))
        for k in range(1, steps + 1):
            for sign in (1.0, -1.0):
                candidate = at(heading_deg + sign * k * HEADING_STEP_DEG, standoff, "oblique")
                if candidate.feasible:
                    return candidate
    return at(heading_deg, max(rng, standoff), "raised")


def _raise(target: Array, standoff: float, known: Array, need: float, axis: Array) -> float | None:
    """The shortest range ≥ `standoff` along `-axis` from the target whose position clears `need` over the known
    points under it (None when moving back never clears them: a line of sight with no vertical part)."""
    if axis[2] <= 1e-6:
        return None
    rng = standoff
    for _ in range(20):  # moving back shifts the footprint too (a tilted camera): iterate to a fixed point
        camera = target - rng * axis
        gap = clearance(camera, known)
        if gap >= need - 1e-9:
            return rng
        rng += (need - gap) / axis[2]
    return None
