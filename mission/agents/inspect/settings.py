"""The inspect agent's tunable numbers (seed 002 §3.4), typed, with their defaults in this one place."""

from __future__ import annotations

from dataclasses import dataclass

from mission.agents.fusion import SPREAD_VIEW_AGREEMENT_M
from mission.agents.hover import WORK_SPEED_M_S
from mission.agents.known_object import FINE_PRIOR_RADIUS_M, FINE_SHIFT_M, FINE_VIEWS, SEARCH_PRIOR_RADIUS_M


@dataclass(frozen=True)
class InspectSettings:
    """Distances in metres, times in seconds, rates in hertz."""

    # viewing a point set
    fine_altitude_m: float = 3.6  # above a set's top for the precise referencing (seed 000's experiments), at least
    search_altitude_m: float = 5.0  # above a set's top while searching: a wide view, at the least
    view_fill: float = 0.75  # a set spans at most this share of the image's width and height while searching
    fine_view_fill: float = 0.9  # ... and in its fine views, closer: the set's position is known to decimetres
    # there, and the stereo depth error grows with the square of the range
    fine_steps_m: tuple[float, ...] = (0.0, 0.4, 0.8)  # successive fine views cycle through these heights above
    # the fine altitude: single-view recognition depends sharply on the range (which corners stand out)
    range_margin_m: float = 0.5  # the set's deepest point stays this far inside the stereo range
    # searching
    search_step_m: float = 1.5  # pattern leg unit: well inside the footprint at the search altitude
    search_positions: int = 9  # pattern positions around each set
    search_raise_m: float = 0.6  # every other ring of the search this much higher
    passing_rate_hz: float = 0.5  # searching, frames taken on the way between positions are tried too, this often
    passing_depth_m: float = 0.5  # ... once the vehicle is within this of the search depth
    # referencing
    settle_s: float = 2.0
    fine_views: int = FINE_VIEWS  # recognised views fused into one fix
    confirm_tries: int = 4  # closer views that may fail to recognise a search hit's set before the hit is dropped
    fine_shift_m: float = FINE_SHIFT_M  # successive fine views move this far along the object's x-axis
    search_prior_radius_m: float = SEARCH_PRIOR_RADIUS_M
    fine_prior_radius_m: float = FINE_PRIOR_RADIUS_M
    tolerance_m: float = 0.05  # pairwise-distance consistency for identification
    view_agreement_m: float = SPREAD_VIEW_AGREEMENT_M  # fine views agree this closely at the fine altitude
    fix_gate_m: float = 0.15  # once placed, a view that moves the set farther than this (plus 3× the assumed
    # odometry drift) from where odometry tracks it is a wrong identification, not a correction
    # the odometry chain
    frame_rate_hz: float = 2.0  # stereo frames while moving by odometry
    vo_drift_per_m: float = 0.01  # assumed odometry drift per metre travelled since the fix
    rereference_drift_m: float = 0.04  # re-reference before a target when the assumed drift exceeds this
    vo_lost_frames: int = 4  # consecutive lost frames that end an odometry chain
    vo_max_step_m: float = 0.5  # a jump larger than this between frames is not motion but a failure
    # The object stands still: odometry may move it in the navigation frame only as far as navigation can drift
    # and jump (USBL fixes move the estimate by up to ~0.3 m a tick, ~0.6 m over an inspection) since the fix,
    # plus a share of the path; beyond that the chain disagrees with navigation and ends
    vo_object_shift_m: float = 1.0
    vo_object_shift_per_m: float = 0.05
    # photographs
    max_range_ratio: float = 1.25  # a viewpoint raised over something too high keeps the target at most this much
    # farther than its standoff (the target still fits the image, its detail ≥ 80 % of the design's); else oblique
    altimeter_samples: int = 5  # altimeter readings while settling at a viewpoint that make its ground known
    altimeter_margin_m: float = 0.05  # measured ground is raised by three times the readings' spread, at least this
    viewpoint_replan_m: float = 0.02  # a viewpoint planned again moves the vehicle when it moves more than this
    viewpoint_replans: int = 2  # at most this many re-plans of one target's viewpoint
    viewpoint_tolerance_m: float = 0.03
    viewpoint_depth_tolerance_m: float = 0.05  # the depth sensor's noise is 2 cm
    photo_interval_s: float = 1.0
    # moving over the object
    set_cost_m: float = 8.0  # a set's search and referencing, in metres of travel, for the ordering
    work_speed_m_s: float = WORK_SPEED_M_S
    clearance_margin_m: float = 1.0  # above the minimum altitude when crossing the object
    altitude_margin_m: float = 0.2  # kept above the mission's minimum altitude, by the altimeter, whatever the plan
    station_radius_m: float = 10.0  # over the object the vehicle hovers from stop to stop (cruising, it would circle)
    over_goal_m: float = 0.6  # descend to a goal's depth only within this horizontal distance of it
