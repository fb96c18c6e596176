"""Geometry checks the coverage tests share."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def circumradii(points: NDArray[np.float64]) -> NDArray[np.float64]:
    """Radius of the circle through each three consecutive points (inf where they are collinear): a path respects a
    turning radius R where none is below R (up to the sampling of its arcs)."""
    a, b, c = points[:-2], points[1:-1], points[2:]
    ab, bc, ca = (np.linalg.norm(b - a, axis=1), np.linalg.norm(c - b, axis=1), np.linalg.norm(a - c, axis=1))
    cross = np.abs((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.asarray(np.where(cross < 1e-9, np.inf, ab * bc * ca / (2.0 * cross)))
