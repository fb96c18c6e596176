"""Seeded survey worlds for `auv bench photo-survey`: a flat patch of seabed with 1–5 objects.

A 40 × 40 m area on a flat seabed at 30 m (1 m information cells; the map and the clearance grid reach 12 m past
the area on every side, room for the turns). Each object is a box 2–7 m long, 1.5–5 m wide, 0.3–1.5 m tall at a
random heading; in odd seeds one of them is a pillar (2 × 2 m, 12 m tall) that reaches through the survey depth,
so the occupancy map matters. The information map is the seed's I = B∗G (`planners.infomap`) of the height map
with 1 m navigation blur; the clearance grid is 0.5 m voxels between 20 and 31 m depth.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from planners.infomap import information_map
from planners.rrt import ClearanceGrid, InformationField

Array = NDArray[np.float64]
SIZE_M = 40.0
PAD_M = 12.0
SEABED_M = 30.0
ALTITUDE_M = 5.0
DEPTH_M = SEABED_M - ALTITUDE_M


@dataclass(frozen=True)
class SurveyWorld:
    seed: int
    objects: int
    area: Array
    field: InformationField
    grid: ClearanceGrid
    height: Array
    pillar: bool


def survey_world(seed: int) -> SurveyWorld:
    """The world of one seed (objects = 1 + seed mod 5)."""
    rng = np.random.default_rng(1000 + seed)
    cell = 1.0
    n = int((SIZE_M + 2 * PAD_M) / cell)
    north0 = east0 = -PAD_M + cell / 2.0
    height = np.zeros((n, n))
    centres = north0 + np.arange(n) * cell
    nn, ee = np.meshgrid(centres, centres, indexing="ij")
    count = 1 + seed % 5
    pillar = seed % 2 == 1
    for k in range(count):
        tall = pillar and k == 0
        c = rng.uniform(4.0, SIZE_M - 4.0, size=2)
        length, width = (2.0, 2.0) if tall else (rng.uniform(2.0, 7.0), rng.uniform(1.5, 5.0))
        h = math.radians(rng.uniform(0.0, 180.0))
        u = (nn - c[0]) * math.cos(h) + (ee - c[1]) * math.sin(h)
        v = -(nn - c[0]) * math.sin(h) + (ee - c[1]) * math.cos(h)
        inside = (np.abs(u) <= length / 2) & (np.abs(v) <= width / 2)
        height[inside] = np.maximum(height[inside], 12.0 if tall else rng.uniform(0.3, 1.5))
    field = InformationField(information_map(height, cell=cell, nav_sigma_m=1.0), north0, east0, cell)
    grid = _grid(height, north0 - cell / 2, east0 - cell / 2, cell)
    area = np.array([[0.0, 0.0], [0.0, SIZE_M], [SIZE_M, SIZE_M], [SIZE_M, 0.0]])
    return SurveyWorld(seed, count, area, field, grid, height, pillar)


def _grid(height: Array, north_lo: float, east_lo: float, cell: float) -> ClearanceGrid:
    """0.5 m voxels from 20 to 31 m depth: occupied below the seabed and inside the objects."""
    voxel = 0.5
    up = int(2 * cell / voxel) // 2
    fine = np.kron(height, np.ones((up, up)))
    top = 20.0
    centres = top + (np.arange(int((SEABED_M + 1.0 - top) / voxel)) + 0.5) * voxel
    occupied = centres[None, None, :] > SEABED_M - fine[:, :, None]
    return ClearanceGrid.from_occupancy(occupied, (north_lo, east_lo, top), voxel)
