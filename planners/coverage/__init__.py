"""Coverage planning for area surveys (seed 002 §2.1): line spacing from the swath and overlap, meander
(boustrophedon) coverage of a polygon minus no-go zones with a boustrophedon cell decomposition, turns within
the vehicle's turning radius, and the single-direction baseline the benchmark compares against.

Polygons are lists of [north, east] pairs in metres (local NED); headings are degrees clockwise from north.
Pure functions: numpy and shapely only.
"""

from .baseline import baseline_boustrophedon
from .metrics import coverage_fraction
from .plan import CoveragePlan
from .planner import meander
from .spacing import line_spacing, line_spacing_over_terrain, swath_width

__all__ = [
    "CoveragePlan",
    "baseline_boustrophedon",
    "coverage_fraction",
    "line_spacing",
    "line_spacing_over_terrain",
    "meander",
    "swath_width",
]
