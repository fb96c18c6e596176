"""The seabed as a seeded height field: mean depth, a planar slope and band-limited roughness.

Depth grows downwards (NED). Queries interpolate bilinearly; scalar queries avoid numpy on the hot path
because the simulator asks once per step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter

from mission.frames import Array
from mission.language.world import Seabed


@dataclass(frozen=True)
class HeightField:
    """Depth samples on a regular grid: `depth[i, j]` at north0 + i·resolution, east0 + j·resolution."""

    depth: Array
    north0: float
    east0: float
    resolution: float

    @property
    def north_max(self) -> float:
        return float(self.north0 + (self.depth.shape[0] - 1) * self.resolution)

    @property
    def east_max(self) -> float:
        return float(self.east0 + (self.depth.shape[1] - 1) * self.resolution)

    def depth_at(self, north: float, east: float) -> float:
        """Bilinear depth at one point; outside the grid the nearest edge value is used."""
        rows, cols = self.depth.shape
        fi = min(max((north - self.north0) / self.resolution, 0.0), rows - 1.000001)
        fj = min(max((east - self.east0) / self.resolution, 0.0), cols - 1.000001)
        i, j = int(fi), int(fj)
        di, dj = fi - i, fj - j
        d = self.depth
        top = d[i, j] * (1.0 - dj) + d[i, j + 1] * dj
        bottom = d[i + 1, j] * (1.0 - dj) + d[i + 1, j + 1] * dj
        return float(top * (1.0 - di) + bottom * di)

    def depths_at(self, north: Array, east: Array) -> Array:
        """Vectorised bilinear depth at many points."""
        rows, cols = self.depth.shape
        fi = np.clip((np.asarray(north) - self.north0) / self.resolution, 0.0, rows - 1.000001)
        fj = np.clip((np.asarray(east) - self.east0) / self.resolution, 0.0, cols - 1.000001)
        i, j = fi.astype(int), fj.astype(int)
        di, dj = fi - i, fj - j
        d = self.depth
        top = d[i, j] * (1.0 - dj) + d[i, j + 1] * dj
        bottom = d[i + 1, j] * (1.0 - dj) + d[i + 1, j + 1] * dj
        return np.asarray(top * (1.0 - di) + bottom * di)

    def grid(self) -> tuple[Array, Array]:
        """North and east coordinates of the grid rows and columns."""
        rows, cols = self.depth.shape
        north = self.north0 + self.resolution * np.arange(rows, dtype=float)
        east = self.east0 + self.resolution * np.arange(cols, dtype=float)
        return north, east


def generate_seabed(spec: Seabed) -> HeightField:
    """Build the height field a `seabed:` block describes; the same spec always gives the same seabed.

    Roughness is white noise low-passed to the given wavelength and scaled to the given standard deviation.
    """
    res = spec.resolution
    rows = int(math.floor((spec.north[1] - spec.north[0]) / res)) + 1
    cols = int(math.floor((spec.east[1] - spec.east[0]) / res)) + 1
    north = spec.north[0] + res * np.arange(rows)
    east = spec.east[0] + res * np.arange(cols)
    n_mid, e_mid = 0.5 * (spec.north[0] + spec.north[1]), 0.5 * (spec.east[0] + spec.east[1])
    depth = spec.mean_depth + spec.slope.north * (north[:, None] - n_mid) + spec.slope.east * (east[None, :] - e_mid)
    rough = spec.roughness
    if rough.amplitude > 0.0:
        rng = np.random.default_rng(rough.seed)
        noise = gaussian_filter(rng.standard_normal((rows, cols)), sigma=rough.wavelength / (2.0 * math.pi * res),
                                mode="wrap")
        noise -= noise.mean()
        std = noise.std()
        if std > 0:
            depth = depth + rough.amplitude * noise / std
    return HeightField(np.ascontiguousarray(depth, dtype=float), float(north[0]), float(east[0]), float(res))
