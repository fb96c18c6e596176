"""What the agents that work over a known object share (seed 002 §3.1–3.4): its pose as the database has it, the
referencing priors, how many recognised fine views make one fix and how far apart they are taken, and the record
of one referencing attempt."""

from __future__ import annotations

from typing import Any

import numpy as np

from mission.frames import pose_matrix
from mission.language.models import KnownObject
from mission.plugin_api import ReferencingResult

FINE_VIEWS = 3  # recognised views fused into one fix
FINE_SHIFT_M = 0.15  # successive fine views move this far along the object's x-axis
SEARCH_PRIOR_RADIUS_M = 4.0  # how far the database pose plus navigation may be off
FINE_PRIOR_RADIUS_M = 0.4  # how far the estimate may be off once a set has been recognised


def database_pose(obj: KnownObject) -> np.ndarray:
    """T_world_object as the database has it (z parallel to the world z, per seed 000 §3.1)."""
    return pose_matrix(obj.pose.north, obj.pose.east, obj.pose.depth, obj.pose.heading)


def attempt_record(result: ReferencingResult) -> dict[str, Any]:
    """The JSON fields of one referencing attempt that both agents log: whether and how well a set was matched,
    and whether the plug-in needed its guided corners for it."""
    return {"recognised": bool(result.recognised), "matched": int(result.matched),
            "residual_m": float(result.residual_rms), "ambiguous": bool(result.ambiguous),
            "cloud_points": int(result.cloud_points), "guided": bool(result.details.get("guided", False))}
