"""OMPL state spaces for the vehicle and the validity checker over a clearance grid (seed 002 §2.2.1–2.2.2).

Two spaces, both in local NED metres:

* `R³` (`RealVectorStateSpace(3)`: north, east, down): a hovering vehicle that can move in any direction.
* Dubins × depth: a `CompoundStateSpace` of OMPL's `DubinsStateSpace` (north, east, yaw; the shortest paths of
  bounded curvature with the horizontal turning radius) and a `RealVectorStateSpace(1)` for depth, with equal
  weights. Interpolation runs along the Dubins curve horizontally and linearly in depth, which is how an AUV
  with independent depth control flies it; the space distance is the Dubins length plus |Δdepth|, never less
  than the 3-D length of the motion. Yaw is the heading in radians (clockwise from north seen from above, i.e.
  counter-clockwise from the north axis towards the east axis in the (north, east) plane Dubins works in).

The validity checker is one lookup: the grid of voxels whose clearance is at least the safety distance plus
half the motion-checking step, flattened into a Python list with a one-voxel border of False, indexed by
truncated offsets (a plain callable is what OMPL 2.x accepts; no Python loop over obstacles).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from planners.rrt import _ompl
from planners.rrt.clearance import ClearanceGrid


@dataclass
class PlanningSpace:
    """An OMPL state space and the conversions between its states and NED points."""

    space: Any
    turning_radius: float | None

    @property
    def dubins(self) -> bool:
        return self.turning_radius is not None

    def make_state(self, point: ArrayLike, heading_deg: float = 0.0) -> Any:
        p = np.asarray(point, dtype=float).reshape(3)
        s = self.space.allocState()
        if self.dubins:
            s[0].setX(float(p[0]))
            s[0].setY(float(p[1]))
            s[0].setYaw(math.radians(heading_deg))
            s[1][0] = float(p[2])
        else:
            s[0], s[1], s[2] = float(p[0]), float(p[1]), float(p[2])
        return s

    def xyz(self, state: Any) -> tuple[float, float, float]:
        if self.dubins:
            return state[0].getX(), state[0].getY(), state[1][0]
        return state[0], state[1], state[2]

    def xy_getter(self) -> Callable[[Any], tuple[float, float]]:
        if self.dubins:
            return lambda s: (s[0].getX(), s[0].getY())
        return lambda s: (s[0], s[1])

    def heading_deg(self, state: Any) -> float:
        return math.degrees(state[0].getYaw()) % 360.0 if self.dubins else float("nan")


def build_space(grid: ClearanceGrid, turning_radius: float | None = None) -> PlanningSpace:
    """R³ over the grid's box, or Dubins (north, east, yaw) × depth when a turning radius is given."""
    base, _, _ = _ompl.load()
    lo = grid.origin
    hi = grid.upper - 1e-9 * grid.cell  # keep sampled states inside the last voxel
    if turning_radius is None:
        space = base.RealVectorStateSpace(3)
        bounds = base.RealVectorBounds(3)
        for a in range(3):
            bounds.setLow(a, float(lo[a]))
            bounds.setHigh(a, float(hi[a]))
        space.setBounds(bounds)
        return PlanningSpace(space, None)
    if not turning_radius > 0:
        raise ValueError(f"turning radius must be positive, got {turning_radius}")
    horizontal = base.DubinsStateSpace(float(turning_radius))
    b2 = base.RealVectorBounds(2)
    for a in range(2):
        b2.setLow(a, float(lo[a]))
        b2.setHigh(a, float(hi[a]))
    horizontal.setBounds(b2)
    depth = base.RealVectorStateSpace(1)
    b1 = base.RealVectorBounds(1)
    b1.setLow(float(lo[2]))
    b1.setHigh(float(hi[2]))
    depth.setBounds(b1)
    space = base.CompoundStateSpace()
    space.addSubspace(horizontal, 1.0)
    space.addSubspace(depth, 1.0)
    return PlanningSpace(space, float(turning_radius))


def validity_checker(grid: ClearanceGrid, required_clearance: float, dubins: bool) -> Callable[[Any], bool]:
    """A callable state → valid: True where the state's voxel has at least `required_clearance`."""
    free = np.zeros(tuple(n + 2 for n in grid.shape), dtype=bool)
    free[1:-1, 1:-1, 1:-1] = grid.distance >= required_clearance
    nx, ny, nz = free.shape
    flat: list[bool] = free.ravel().tolist()
    x0, y0, z0 = (float(v) for v in grid.origin - grid.cell)  # the border voxel starts one cell out
    inv = 1.0 / grid.cell

    # int() truncates towards zero, so offsets in (−1, 0) land on the border (False) and below −1 go negative.
    if dubins:
        def valid_dubins(s: Any, f: list[bool] = flat) -> bool:
            h = s[0]
            i = int((h.getX() - x0) * inv)
            j = int((h.getY() - y0) * inv)
            k = int((s[1][0] - z0) * inv)
            if 0 <= i < nx and 0 <= j < ny and 0 <= k < nz:
                return f[(i * ny + j) * nz + k]
            return False

        return valid_dubins

    def valid(s: Any, f: list[bool] = flat) -> bool:
        i = int((s[0] - x0) * inv)
        j = int((s[1] - y0) * inv)
        k = int((s[2] - z0) * inv)
        if 0 <= i < nx and 0 <= j < ny and 0 <= k < nz:
            return f[(i * ny + j) * nz + k]
        return False

    return valid
