"""Mission language v1: YAML missions → typed, immutable models, validated with every mistake located."""

from mission.language.loader import load_mission, load_world, mission_schema, validate_mission_file
from mission.language.models import Mission, RouteElement

__all__ = ["Mission", "RouteElement", "load_mission", "load_world", "mission_schema", "validate_mission_file"]
