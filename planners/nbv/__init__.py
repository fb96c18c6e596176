"""Next-best-view 3-D scanning of a large object (seed 002 §2.2.2).

Candidate viewpoints on a safe shell around the known structure, in known-free space; visibility by ray-casting
the scanner frustum through the voxel map; the seed's utility u = (d·w_d + f/max f·w_f + ct/max ct·w_ct)·ol;
an `NbvPlanner` an explore agent drives (`propose`, `integrate`); the exploration loop with safe RRT connections
between views; a receding-horizon baseline in the style of Bircher et al. 2016 (`planners.nbv.baseline`); and a
synthetic box-and-cylinder scene with an exact-ray-casting scanner for tests and benchmarks; and, for the
`reconstruct` goal, how well a stereo camera has seen the mapped surface (`planners.nbv.stereo`).
"""

from planners.nbv.baseline import RecedingHorizonNbv
from planners.nbv.candidates import candidate_views, is_safe, is_safe_view
from planners.nbv.completeness import Completeness, surface_completeness
from planners.nbv.derived import DerivedMaps, contour_mask
from planners.nbv.explore import ExplorationLog, connect, explore, run_exploration, segment_safe
from planners.nbv.grid import FREE, OCCUPIED, UNKNOWN, StateGrid
from planners.nbv.planner import NbvPlanner, Scan
from planners.nbv.scene import Box, Cylinder, Scene, survey_scans
from planners.nbv.stereo import (
    MAX_INCIDENCE_DEG,
    USEFUL_RANGE_SHARE,
    Camera,
    StereoCoverage,
    camera_candidates,
    camera_rotations,
    reconstruct_utility,
    seen_from,
    stereo_gain,
    surface_normals,
)
from planners.nbv.utility import CONTOUR, FRONTIER, ViewTerms, Weights, next_best_view, utility_terms, view_utility
from planners.nbv.views import Scanner, View, Views
from planners.nbv.visibility import Visibility, visibility

__all__ = [
    "MAX_INCIDENCE_DEG",
    "USEFUL_RANGE_SHARE",
    "Camera",
    "StereoCoverage",
    "camera_candidates",
    "camera_rotations",
    "reconstruct_utility",
    "seen_from",
    "stereo_gain",
    "surface_normals",
    "CONTOUR",
    "Completeness",
    "FREE",
    "OCCUPIED",
    "UNKNOWN",
    "FRONTIER",
    "Box",
    "Cylinder",
    "DerivedMaps",
    "ExplorationLog",
    "NbvPlanner",
    "RecedingHorizonNbv",
    "Scan",
    "Scanner",
    "Scene",
    "StateGrid",
    "View",
    "ViewTerms",
    "Views",
    "Visibility",
    "Weights",
    "candidate_views",
    "is_safe_view",
    "connect",
    "contour_mask",
    "explore",
    "next_best_view",
    "run_exploration",
    "is_safe",
    "segment_safe",
    "survey_scans",
    "utility_terms",
    "view_utility",
    "visibility",
    "surface_completeness",
]
