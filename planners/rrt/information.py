"""Information-weighted path cost: RRT node evaluation that favours informative areas (seed 002 §2.2.1).

The seed lets the RRT prefer nodes by an evaluation function so that the most informative areas of the
information map I = B∗G (§2.1, `planners.infomap`) get a denser net of passes. Here that preference is a cost:
a metre flown over a cell of normalised information Î ∈ [0, 1] costs

    w(Î) = (1 − α·Î) / (1 − α)          (α = `discount` ∈ [0, 1))

so a metre over the most informative cell costs (1 − α) of a metre over a blank one, and w ≥ 1 everywhere. The
last property keeps OMPL's path-length heuristics admissible (cost ≥ length), so the objective subclasses
`PathLengthOptimizationObjective` and InformedRRT*'s ellipsoidal sampling and BIT*'s ordering stay valid. The
cost goes through `motionCost` (OMPL 2.x ignores a Python `stateCost`).

>>> import numpy as np
>>> f = InformationField(np.array([[0.0, 2.0]]), north0=0.0, east0=0.0, cell=1.0)
>>> f.normalised_at([[0.0, 1.0, 5.0], [0.0, 0.2, 5.0], [9.0, 9.0, 5.0]]).tolist()
[1.0, 0.0, 0.0]
>>> round(float(weight(np.array(1.0), 0.8)), 6), round(float(weight(np.array(0.0), 0.8)), 6)
(1.0, 5.0)
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from planners.rrt import _ompl

Array = NDArray[np.float64]
XYGetter = Callable[[Any], tuple[float, float]]


@dataclass(frozen=True)
class InformationField:
    """A 2-D information map: cell (i, j) is centred at (north0 + i·cell, east0 + j·cell) (`planners.infomap`)."""

    values: Array
    north0: float
    east0: float
    cell: float

    def __post_init__(self) -> None:
        if np.asarray(self.values).ndim != 2:
            raise ValueError(f"information map must be 2-D, got shape {np.shape(self.values)}")
        if not self.cell > 0:
            raise ValueError(f"cell must be positive, got {self.cell}")

    def normalised(self) -> Array:
        """Î = I / max I (zeros when the map is blank); NaN counts as 0."""
        v = np.nan_to_num(np.asarray(self.values, dtype=float), nan=0.0)
        top = float(v.max()) if v.size else 0.0
        return v / top if top > 0 else np.zeros_like(v)

    def cell_of(self, north: ArrayLike, east: ArrayLike) -> tuple[NDArray[np.int64], NDArray[np.int64],
                                                                    NDArray[np.bool_]]:
        """Row, column of the nearest cell centre, and whether that cell is on the map."""
        i = np.floor((np.asarray(north, dtype=float) - self.north0) / self.cell + 0.5).astype(np.int64)
        j = np.floor((np.asarray(east, dtype=float) - self.east0) / self.cell + 0.5).astype(np.int64)
        rows, cols = np.shape(self.values)
        return i, j, (i >= 0) & (i < rows) & (j >= 0) & (j < cols)

    def normalised_at(self, points: ArrayLike) -> Array:
        """Î at points (N, ≥2) by their north and east; 0 off the map."""
        p = np.atleast_2d(np.asarray(points, dtype=float))
        i, j, on = self.cell_of(p[:, 0], p[:, 1])
        out = np.zeros(len(p))
        out[on] = self.normalised()[i[on], j[on]]
        return out


def weight(info: Array, discount: float) -> Array:
    """Cost per metre w(Î) = (1 − α·Î) / (1 − α) ≥ 1."""
    if not 0.0 <= discount < 1.0:
        raise ValueError(f"discount must lie in [0, 1), got {discount}")
    return (1.0 - discount * np.asarray(info, dtype=float)) / (1.0 - discount)


def resample(points: ArrayLike, spacing: float) -> Array:
    """A polyline (K, 3) resampled at ≤ `spacing` metres (vertices kept)."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    if len(p) < 2:
        return p.copy()
    out = [p[:1]]
    for a, b in zip(p[:-1], p[1:], strict=True):
        n = max(1, math.ceil(float(np.linalg.norm(b - a)) / spacing))
        t = np.arange(1, n + 1)[:, None] / n
        out.append(a + t * (b - a))
    return np.concatenate(out)


def path_information(points: ArrayLike, field: InformationField) -> float:
    """∫ Î ds along a polyline (metres of fully informative ground flown over), by the midpoint rule."""
    p = resample(points, field.cell / 4.0)
    if len(p) < 2:
        return 0.0
    mid = 0.5 * (p[1:] + p[:-1])
    ds = np.linalg.norm(np.diff(p, axis=0), axis=1)
    return float(np.sum(field.normalised_at(mid) * ds))


def path_cost(points: ArrayLike, field: InformationField | None, discount: float) -> float:
    """The objective's cost of a polyline (its length when there is no field)."""
    p = resample(points, field.cell / 4.0 if field is not None else 1e9)
    if len(p) < 2:
        return 0.0
    ds = np.linalg.norm(np.diff(p, axis=0), axis=1)
    if field is None:
        return float(ds.sum())
    return float(np.sum(weight(field.normalised_at(0.5 * (p[1:] + p[:-1])), discount) * ds))


def information_objective(si: Any, field: InformationField | None, discount: float, xy: XYGetter,
                          path_length_base: bool = True) -> Any:
    """An OMPL objective whose motion cost is the space distance times the mean w(Î) along the motion.

    Î is sampled on the horizontal chord of the motion (for Dubins motions the arc stays within a turning
    radius of it) at the midpoints of equal steps about two cells long (at most 32; the information map is
    Gaussian-blurred, so smooth at that scale), in plain Python over a flat list: RRT* calls this a few hundred
    times per iteration. Without a field the cost is the space distance.

    `path_length_base` derives from `PathLengthOptimizationObjective` (R³: OMPL's direct informed sampling
    applies); otherwise from the bare `OptimizationObjective` with the space distance as the motion-cost
    heuristic (what Dubins × depth needs: OMPL's direct informed sampler rejects compound spaces).
    """
    cls = _objective_class(path_length_base)
    return cls(si, field, discount, xy)


@cache
def _objective_class(path_length_base: bool) -> type:
    base, _, _ = _ompl.load()
    parent = base.PathLengthOptimizationObjective if path_length_base else base.OptimizationObjective

    class InformationObjective(parent):  # type: ignore[misc, valid-type]
        def __init__(self, si: Any, field: InformationField | None, discount: float, xy: XYGetter) -> None:
            super().__init__(si)
            self.si = si
            self.xy = xy
            self.cost_type = base.Cost
            self.weighted = field is not None
            if field is None:
                return
            w = weight(field.normalised(), discount)
            self.rows, self.cols = w.shape
            self.weights: list[float] = w.ravel().tolist()
            self.w_off = 1.0 / (1.0 - discount)
            self.n0, self.e0, self.inv = field.north0, field.east0, 1.0 / field.cell

        def stateCost(self, s: Any) -> Any:  # noqa: N802 - OMPL's names; pure virtual in the bare objective
            return self.cost_type(0.0)

        def motionCostHeuristic(self, s1: Any, s2: Any) -> Any:  # noqa: N802
            return self.cost_type(self.si.distance(s1, s2))

        def motionCost(self, s1: Any, s2: Any) -> Any:  # noqa: N802
            dist = self.si.distance(s1, s2)
            if not self.weighted:
                return self.cost_type(dist)
            x1, y1 = self.xy(s1)
            x2, y2 = self.xy(s2)
            inv = self.inv
            a0 = (x1 - self.n0) * inv + 0.5
            b0 = (y1 - self.e0) * inv + 0.5
            da, db = (x2 - x1) * inv, (y2 - y1) * inv
            # One sample per two cells (the map is Gaussian-blurred, so smooth at that scale), at most 32.
            n = min(int(math.hypot(da, db) * 0.5) + 1, 32)
            da /= n
            db /= n
            a = a0 + 0.5 * da
            b = b0 + 0.5 * db
            rows, cols, weights, w_off = self.rows, self.cols, self.weights, self.w_off
            total = 0.0
            for _ in range(n):
                if 0.0 <= a < rows and 0.0 <= b < cols:
                    total += weights[int(a) * cols + int(b)]
                else:
                    total += w_off
                a += da
                b += db
            return self.cost_type(dist * total / n)

    return InformationObjective
