"""Objects found as anomalies of the survey maps (seed 002 §2.1): cells where the information map is high and
the sensed surface stands above the local seabed, grouped into connected components, each measured for position,
footprint (length, width, orientation) and height.

The local seabed is a robust background: a wide median of the sensed depth, so that objects smaller than the
window stand out of it while slopes and long-wave roughness do not.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from planners.infomap import fill_unknown

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Detection:
    """An anomaly in world coordinates (NED metres, heading of the long axis in degrees from north)."""

    north: float
    east: float
    length: float
    width: float
    heading_deg: float
    height: float
    top_depth: float
    score: float
    cells: int


def seabed_background(depth: Array, cell: float, window_m: float) -> Array:
    """Local seabed depth under each cell: a median over a window much wider than the objects sought."""
    filled, _ = fill_unknown(depth)
    size = max(3, int(round(window_m / cell)) | 1)
    return np.asarray(ndimage.median_filter(filled, size=size, mode="nearest"))


def _footprint(north: Array, east: Array, cell: float) -> tuple[float, float, float]:
    """Length, width and long-axis heading of a set of cell centres (principal axes, cell size included)."""
    if len(north) < 3:
        return cell, cell, 0.0
    pts = np.column_stack([north - north.mean(), east - east.mean()])
    _, vecs = np.linalg.eigh(np.cov(pts.T))
    axis = vecs[:, -1]
    along = pts @ axis
    across = pts @ vecs[:, 0]
    heading = math.degrees(math.atan2(axis[1], axis[0])) % 180.0
    return float(np.ptp(along) + cell), float(np.ptp(across) + cell), heading


def detect_anomalies(depth: Array, north0: float, east0: float, cell: float, info: Array, *,
                     info_threshold: float | None = None, min_height: float = 0.5,
                     footprint_height: float | None = None, min_area_m2: float = 1.0,
                     background_window_m: float = 25.0) -> list[Detection]:
    """Anomalies of a sensed-depth map (`depth[i, j]` at north0 + i·cell, east0 + j·cell; NaN = unseen).

    Cells standing at least `footprint_height` (default: half of `min_height`) above the local seabed form
    components; a component is an object when its highest cell stands at least `min_height` above the seabed
    and it touches cells where the information map exceeds `info_threshold` (default: a robust 8-MAD level above
    the median of observed cells, with a floor of 0.2 m/m). Components smaller than `min_area_m2` are noise.
    """
    depth = np.asarray(depth, dtype=float)
    known = np.isfinite(depth)
    if not known.any():
        return []
    background = seabed_background(depth, cell, background_window_m)
    relief = np.where(known, background - depth, 0.0)  # height above the local seabed
    observed = info[known]
    if info_threshold is None:
        median = float(np.median(observed))
        mad = float(np.median(np.abs(observed - median))) * 1.4826
        info_threshold = max(median + 8.0 * mad, 0.2)
    footprint_height = 0.5 * min_height if footprint_height is None else footprint_height
    raised = known & (relief >= footprint_height)
    salient = ndimage.binary_dilation(info > info_threshold, iterations=2)
    # Keep raised components that touch an informative edge; the whole raised body gives the footprint.
    labels, count = ndimage.label(raised, structure=np.ones((3, 3)))
    out = []
    for k in range(1, count + 1):
        mask = labels == k
        if not (mask & salient).any() or mask.sum() * cell * cell < min_area_m2 or relief[mask].max() < min_height:
            continue
        ii, jj = np.nonzero(mask)
        north = np.asarray(north0 + ii * cell, dtype=np.float64)
        east = np.asarray(east0 + jj * cell, dtype=np.float64)
        weights = relief[mask]
        length, width, heading = _footprint(north, east, cell)
        out.append(Detection(
            north=float(np.average(north, weights=weights)), east=float(np.average(east, weights=weights)),
            length=length, width=width, heading_deg=heading, height=float(relief[mask].max()),
            top_depth=float(depth[mask].min()),
            score=float(info[mask].max()), cells=int(mask.sum())))
    return sorted(out, key=lambda d: -d.height)
