"""What the inspect agent knows lies round an object's targets, and the viewpoints it plans from that (issue 21
item 4; `viewpoint.plan_viewpoint` is the rule): the database's points (characteristic points and targets) and
what the altimeter measured under the vehicle at viewpoints (an uncharted tarpaulin over a valve panel). All of it
is kept in the object frame, so that it moves with the object as referencing and odometry place it; all of it is
estimate, never truth."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

from mission.agents.inspect.viewpoint import Viewpoint, plan_viewpoint
from mission.geometry import invert, transform_points
from mission.language.models import Target


@dataclass(frozen=True)
class PlannedView:
    """A target's planned viewpoint: the camera position in the object frame, the vehicle's heading, and the plan
    behind them (world coordinates as of planning)."""

    camera_object: np.ndarray
    heading_deg: float
    plan: Viewpoint


@dataclass
class Surroundings:
    """Known points round the object (object frame, z down) and the altitude floor viewpoints must keep (the
    mission's minimum altitude plus the agent's margin, metres); `tilt_deg` is the camera's mount."""

    database: np.ndarray
    floor_m: float
    tilt_deg: float
    max_range_ratio: float
    measured: list[np.ndarray] = field(default_factory=list)  # altimeter grounds, already raised by their margin

    @classmethod
    def of(cls, points: Iterable[np.ndarray], floor_m: float, tilt_deg: float,
           max_range_ratio: float) -> Surroundings:
        return cls(np.vstack([np.asarray(p, dtype=float).reshape(-1, 3) for p in points]), floor_m, tilt_deg,
                   max_range_ratio)

    def measure(self, T_wo: np.ndarray, samples: np.ndarray, min_margin_m: float) -> np.ndarray:
        """Keep the ground the altimeter saw (`samples`: N × (north, east, ground depth) in the navigation frame)
        as a known point: at the samples' mean position and median ground, raised by three times their spread
        (the altimeter's noise, so that the vehicle at the floor is not pushed up by every noisy reading), at
        least `min_margin_m`. Returns the point (object frame)."""
        ground = np.array([samples[:, 0].mean(), samples[:, 1].mean(), float(np.median(samples[:, 2]))])
        margin = max(min_margin_m, 3.0 * float(np.std(samples[:, 2])))
        ground[2] -= margin
        point = np.asarray(transform_points(invert(T_wo), ground[None, :])[0], dtype=float)
        self.measured.append(point)
        return point

    def known_world(self, T_wo: np.ndarray) -> np.ndarray:
        """Every known point in the navigation frame as the object is placed now."""
        points = np.vstack([self.database, *[m[None, :] for m in self.measured]])
        return np.asarray(transform_points(T_wo, points), dtype=float)

    def plan(self, target: Target, T_wo: np.ndarray, heading_deg: float) -> PlannedView:
        """The target's nearest feasible viewpoint from what is known now (`heading_deg`: the designed heading)."""
        target_world = transform_points(T_wo, np.asarray([target.at], dtype=float))[0]
        plan = plan_viewpoint(target_world, target.standoff, self.known_world(T_wo), self.floor_m, heading_deg,
                              self.tilt_deg, self.max_range_ratio)
        camera = transform_points(invert(T_wo), plan.camera[None, :])[0]
        return PlannedView(np.asarray(camera, dtype=float), plan.heading_deg, plan)
