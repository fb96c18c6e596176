"""Line spacing of an area survey from the sonar swath and the required overlap (seed 002 §2.1).

The swath of a multibeam echo-sounder (or side-scan) at altitude h with a fan aperture α is 2·h·tan(α/2); lines
are laid `swath·(1 − overlap/100)` apart. The terrain taken into account: the vehicle holds its depth over the
area, so where the seabed rises above its mean the altitude, and with it the swath, shrinks; the spacing is taken
at the smallest altitude the terrain allows, so that the overlap holds over the highest ground too.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike


def swath_width(altitude: float, aperture_deg: float) -> float:
    """Across-track width of the seabed strip seen at `altitude` by a fan of `aperture_deg` degrees.

    >>> round(swath_width(20.0, 120.0), 2)
    69.28
    >>> round(swath_width(10.0, 90.0), 2)
    20.0
    """
    if altitude <= 0.0:
        raise ValueError(f"altitude must be positive, got {altitude}")
    if not 0.0 < aperture_deg < 180.0:
        raise ValueError(f"aperture must be in (0, 180) degrees, got {aperture_deg}")
    return 2.0 * altitude * math.tan(math.radians(aperture_deg) / 2.0)


def line_spacing(altitude: float, aperture_deg: float, overlap_percent: float, relief: float = 0.0) -> float:
    """Distance between survey lines: the swath at `altitude − relief` times `(1 − overlap/100)`.

    `relief` is how far the seabed rises above its mean under the area (metres, ≥ 0): the terrain taken into
    account, the swath is narrowest over the highest ground, and the spacing is computed there.

    >>> round(line_spacing(20.0, 120.0, 20.0), 2)
    55.43
    >>> round(line_spacing(20.0, 120.0, 20.0, relief=5.0), 2)
    41.57
    """
    if not 0.0 <= overlap_percent < 100.0:
        raise ValueError(f"overlap must be in [0, 100) percent, got {overlap_percent}")
    if relief < 0.0:
        raise ValueError(f"relief must be non-negative, got {relief}")
    if relief >= altitude:
        raise ValueError(f"the seabed rises {relief} m, to or above the survey altitude of {altitude} m")
    return swath_width(altitude - relief, aperture_deg) * (1.0 - overlap_percent / 100.0)


def line_spacing_over_terrain(
    altitude: float,
    aperture_deg: float,
    overlap_percent: float,
    seabed_depths: ArrayLike,
    percentile: float = 95.0,
) -> float:
    """Line spacing over a known seabed: the relief is a high percentile of how far the seabed rises above its mean.

    `seabed_depths` are depths (positive down, metres) sampled under the area; NaNs are ignored. A percentile
    rather than the maximum keeps one spike (a wellhead, a boulder) from shrinking the spacing of the whole survey.

    >>> depths = [100.0, 100.0, 100.0, 96.0]          # mean 99, highest ground 3 m above it
    >>> round(line_spacing_over_terrain(20.0, 120.0, 20.0, depths, percentile=100.0), 2)
    47.11
    """
    depths = np.asarray(seabed_depths, dtype=float).ravel()
    depths = depths[np.isfinite(depths)]
    if depths.size == 0:
        raise ValueError("no finite seabed depth given")
    rise = float(np.mean(depths)) - depths
    relief = max(0.0, float(np.percentile(rise, percentile)))
    return line_spacing(altitude, aperture_deg, overlap_percent, relief)
