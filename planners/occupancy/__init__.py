"""Voxel occupancy from multibeam sonar with Bayes (log-odds) updates, seed 002 §2.1.

`VoxelMap` fuses pings (free along each beam, occupied at its end, OctoMap's sensor model and clamping) into
sparse blocked storage and projects the result to a height map for the information map of `planners.infomap`.
Pure numpy; no simulator imports.
"""

from planners.occupancy.logodds import LogOddsParams, logit, probability
from planners.occupancy.projection import column_reduce, grid_shape
from planners.occupancy.raycast import ray_voxels
from planners.occupancy.voxelmap import VoxelMap

__all__ = ["LogOddsParams", "VoxelMap", "column_reduce", "grid_shape", "logit", "probability", "ray_voxels"]
