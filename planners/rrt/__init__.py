"""RRT planning in the voxel occupancy map (seed 002 §2.2.1 photo survey, §2.2.2 safe routes between views).

OMPL (2.x, imported lazily) plans in a clearance grid built from occupied (and, as configured, unknown) voxels,
in R³ or in Dubins × depth for the vehicle's turning radius, optionally with an information-weighted cost that
makes optimal paths run over informative cells; `photo_survey_path` covers a flat object's area with camera
passes spaced densest where the information map is highest; `informative_survey_path` photographs it under a path
budget along a rapidly-exploring information-gathering tree (RIG) grown over the information map.
"""

from planners.rrt.clearance import ClearanceGrid
from planners.rrt.information import InformationField, path_cost, path_information
from planners.rrt.photo import PhotoSurvey, photo_survey_path
from planners.rrt.planning import PLANNERS, PathResult, plan_path
from planners.rrt.rig_survey import InformativeSurvey, informative_survey_path

__all__ = [
    "PLANNERS",
    "ClearanceGrid",
    "InformationField",
    "InformativeSurvey",
    "PathResult",
    "PhotoSurvey",
    "informative_survey_path",
    "path_cost",
    "path_information",
    "photo_survey_path",
    "plan_path",
]
