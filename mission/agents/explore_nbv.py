"""Next-best-view scanning of one object (seed 002 §2.2.2) for the `explore` agent: the planner for a scanner
fixed to the hull, the object's region that the frontier and contour terms count, scanner frames as the planner
takes them, and the record of one object's exploration (`TargetRun`) with the map's own coverage estimate."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from mission.agents.explore_region import Target
from mission.frames import rotation_zyx
from mission.vehicle import ScanFrame
from planners.nbv import NbvPlanner, Scan, View, Views
from planners.nbv.grid import FREE, UNKNOWN, StateGrid

FOCUS_MARGIN_M = 1.5  # the object's region: its footprint's circle and its height grown by this much


@dataclass
class FixedMountNbv(NbvPlanner):
    """`NbvPlanner` for a scanner fixed to the hull: every candidate has the mount's pitch (the vehicle can turn
    to any heading but keeps its pitch).

    With a `focus` (a boolean mask over the state grid: the object's region), the frontier and contour terms count
    the object only: unknown voxels outside the focus (the seabed's shadows around it, which the survey left and
    no view of the object needs) are free for visibility, and only contour voxels inside it count and anchor
    candidates. Safety is unchanged: candidates and paths use the true states' safety grid, where unknown space
    is an obstacle.
    """

    pitch_deg: float = -25.0
    focus: np.ndarray | None = None

    def utility_grid(self) -> tuple[StateGrid, np.ndarray]:
        """The state grid the utility sees, and the contour ids that count."""
        contour = self.derived.contour_ids()
        if self.focus is None:
            return self.grid, contour
        states = self.grid.states.copy()
        states[(states == UNKNOWN) & ~self.focus] = FREE
        return StateGrid(states, self.grid.key_lo, self.grid.resolution), contour[self.focus.reshape(-1)[contour]]

    def mounted(self, views: Views) -> Views:
        return Views(views.positions, views.heading_deg, np.full(len(views), self.pitch_deg))


def object_region(grid: StateGrid, target: Target, seabed: float) -> np.ndarray:
    """Mask of the grid voxels around the object: within `FOCUS_MARGIN_M` of its footprint's circle, from above
    its top down to just under the seabed."""
    ijk = np.indices(grid.shape).reshape(3, -1).T
    c = grid.centres(ijk)
    near = np.hypot(c[:, 0] - target.north, c[:, 1] - target.east) <= target.radius + FOCUS_MARGIN_M
    level = (c[:, 2] >= target.top_depth - FOCUS_MARGIN_M) & (c[:, 2] <= seabed + 0.25)
    return np.asarray((near & level).reshape(grid.shape))


def scan_of(frame: ScanFrame) -> Scan:
    """A scanner frame placed at its estimated pose (flat attitude), as the planner takes it."""
    origin = np.array([frame.north, frame.east, frame.depth])
    dirs = frame.directions_body @ rotation_zyx(frame.heading).T
    return Scan(origin, origin + dirs * frame.ranges[:, None], frame.hit)


def mount_tilt_deg(frame: ScanFrame) -> float:
    """The scanner's downward tilt, from the mean direction of its rays."""
    mean = frame.directions_body.mean(axis=0)
    return math.degrees(math.asin(float(mean[2] / np.linalg.norm(mean))))


@dataclass
class TargetRun:
    """One target's exploration: its planner and what happened."""

    target: Target
    planner: FixedMountNbv
    lo: np.ndarray
    hi: np.ndarray
    seabed: float
    start: View
    views: list[tuple[float, float, float, float, float]] = field(default_factory=list)
    iterations_ms: list[float] = field(default_factory=list)
    integrate_ms: list[float] = field(default_factory=list)
    volume: list[tuple[float, float, float]] = field(default_factory=list)  # time, known m³, coverage estimate
    rejected: int = 0
    replans: int = 0
    stop_reason: str = ""
    estimate: float = 0.0
    focus_done_at: float | None = None
    """When the object's region had nothing left to reveal (then the whole box is explored)."""

    def object_voxels(self) -> np.ndarray:
        """Flat grid ids of the occupied voxels that belong to the object (above the seabed, over its footprint)."""
        grid = self.planner.grid
        ids = grid.occupied_ids
        c = grid.centres(np.stack(np.unravel_index(ids, grid.shape), axis=1))
        t = self.target
        near = np.hypot(c[:, 0] - t.north, c[:, 1] - t.east) <= t.radius + 1.5
        return np.asarray(ids[near & (c[:, 2] < self.seabed - 0.4)])

    def expected_voxels(self) -> float:
        """Surface voxels the detection's box would have: its top and four sides."""
        t, res = self.target, self.planner.grid.resolution
        height = max(self.seabed - t.top_depth, 0.0)
        return (t.length * t.width + 2.0 * (t.length + t.width) * height) / res**2

    def coverage_estimate(self) -> float:
        """The map's own estimate of the object's observed surface: the share of its mapped voxels off the open
        contour (seen with their surroundings), times how many are mapped against what its detected box would
        have (so that a few voxels seen early do not pass for a finished model)."""
        ids = self.object_voxels()
        if not len(ids):
            return 0.0
        open_edge = self.planner.derived.contour.reshape(-1)[ids]
        return float((1.0 - open_edge.mean()) * min(1.0, len(ids) / max(self.expected_voxels(), 1.0)))
