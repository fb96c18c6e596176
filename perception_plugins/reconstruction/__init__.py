"""3D reconstruction of explored objects from stereo pairs at known camera poses (seed 003 "3D reconstruction";
seed 002's exploration deliverable, a detailed 3D model of an unknown object).

Pure algorithms, arrays in and arrays out: `depth` (range maps), `tsdf` (hashed TSDF fusion), `mesh` (marching
cubes with colour), `clean` (artefact removal), `keypoints` (characteristic-point sets for a database entry) and
`pipeline` (all of them in order).
"""

from __future__ import annotations

from perception_plugins.reconstruction.clean import CleanSettings, clean_mesh
from perception_plugins.reconstruction.depth import RangeMap, RangeSettings, points_from_range, range_map
from perception_plugins.reconstruction.mesh import Mesh, extract_mesh
from perception_plugins.reconstruction.pipeline import (
    Reconstruction,
    ReconstructionSettings,
    StereoView,
    fuse_range_maps,
    fuse_views,
)
from perception_plugins.reconstruction.tsdf import HashedTsdf

__all__ = ["CleanSettings", "HashedTsdf", "Mesh", "RangeMap", "RangeSettings", "Reconstruction",
           "ReconstructionSettings", "StereoView", "clean_mesh", "extract_mesh", "fuse_range_maps", "fuse_views",
           "points_from_range", "range_map"]
