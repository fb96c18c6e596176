"""The explore planner's `reconstruct` goal (issue 22): next-best views for the stereo camera as well as the
scanner, so that a reconstruction (`auv reconstruct`) gets every face of the object at a useful range and
incidence.

`ReconstructNbv` is the fixed-mount planner with a per-voxel record of how well the stereo camera has seen each
occupied voxel of the object's region (`planners.nbv.StereoCoverage`: in the frustum, within
`USEFUL_RANGE_SHARE` of the stereo range, at most `MAX_INCIDENCE_DEG` off the surface normal, not hidden),
updated with the camera's *estimated* pose at each stereo pair the vehicle delivers; candidates are drawn on a
shell that keeps the anchor surface within the useful range of the camera (never nearer than the planning
distance), candidates aimed at surface not yet seen well are added (`planners.nbv.camera_candidates`: the
surface at the image centre, in range, faced), and the utility adds the voxels a candidate's camera would newly see well
(`planners.nbv.reconstruct_utility`, weight `STEREO_WEIGHT`). The element stops when the share of the mapped
surface seen well, times how far the object is bounded (`TargetRun.bounded`), reaches `STEREO_TARGET`. When no
path leaves the vehicle's position (a view near the planning distance, then a frame that reveals more structure),
it climbs clear first (`climb_clear`) instead of giving the view up.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mission.agents.base import AgentContext
from mission.agents.explore_nbv import FixedMountNbv, TargetRun
from mission.language.models import Explore, Mission, Stereo
from mission.language.mount import R_body_cam_of
from mission.vehicle import Observation
from planners.nbv import (
    Camera,
    StereoCoverage,
    Views,
    camera_candidates,
    camera_rotations,
    is_safe,
    reconstruct_utility,
    stereo_gain,
    surface_normals,
)

STEREO_TARGET = 0.90
"""The element stops once this share of the object's mapped surface was seen well by the stereo camera."""
CAMERA_CANDIDATES = 100
"""Candidates aimed at unseen surface (`planners.nbv.camera_candidates`) added to the shell's at each proposal."""
STEREO_WEIGHT = 0.6
"""Weight of the stereo term against the seed's utility (which keeps the map growing and the moves short)."""
GAIN_SCALE = 0.05
"""The stereo gain is normalised by at least this share of the object's mapped surface voxels
(`planners.nbv.reconstruct_utility`'s `scale`)."""


def camera_of(stereo: Stereo) -> Camera:
    """The planner's model of the mission's stereo camera (`sensors.stereo`, its mount included)."""
    return Camera.of_stereo(stereo.width, stereo.height, stereo.fx, stereo.max_range, R_body_cam_of(stereo))


@dataclass
class ReconstructNbv(FixedMountNbv):
    """`FixedMountNbv` that also plans for the stereo camera (the module docstring); `region` (a mask over the
    grid: the object's region above the seabed) says which occupied voxels are the object's surface."""

    camera: Camera | None = None
    region: NDArray[np.bool_] | None = None
    coverage: StereoCoverage = field(init=False)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.camera is None:
            raise ValueError("the reconstruct goal needs a stereo camera")
        self.coverage = StereoCoverage(self.camera, self.grid.shape)

    def surface_ids(self) -> NDArray[np.int64]:
        """Flat ids of the occupied voxels of the object's region (all occupied voxels without a region)."""
        ids = self.grid.occupied_ids
        return ids if self.region is None else np.asarray(ids[self.region.reshape(-1)[ids]])

    def add_pose(self, north: float, east: float, depth: float, heading_deg: float) -> None:
        """A stereo pair taken with the vehicle (level) at this estimated pose."""
        assert self.camera is not None
        self.coverage.add_pose((north, east, depth), camera_rotations([heading_deg], self.camera.R_body_cam)[0])

    def stereo_share(self) -> float:
        """Bring the coverage record up to date; the share of the object's mapped surface seen well."""
        return self.coverage.update(self.grid, self.surface_ids())

    def unseen(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Centres and normals of the object's mapped surface voxels not yet seen well."""
        ids = self.surface_ids()
        todo = ids[~self.coverage.well.reshape(-1)[ids]]
        ijk = np.stack(np.unravel_index(todo, self.grid.shape), axis=1)
        return self.grid.centres(ijk), surface_normals(self.grid.states, ijk)

    def extra_candidates(self) -> Views:
        assert self.camera is not None
        self.stereo_share()  # the record up to date with the poses and map so far (a no-op when it is)
        points, normals = self.unseen()
        views = camera_candidates(self.grid, self.safety, points, normals, self.camera, count=CAMERA_CANDIDATES,
                                  near=self.safe_distance + self.safety.cell, safe_distance=self.safe_distance,
                                  rng=self.rng)
        return self.mounted(views)

    def extra_gain(self, views: Views) -> NDArray[np.int64]:
        assert self.camera is not None
        points, normals = self.unseen()
        return stereo_gain(self.grid, points, normals, views.positions,
                           camera_rotations(views.heading_deg, self.camera.R_body_cam), self.camera)

    def with_extra(self, u: NDArray[np.float64], extra: NDArray[np.int64]) -> NDArray[np.float64]:
        return reconstruct_utility(u, extra, STEREO_WEIGHT, scale=GAIN_SCALE * len(self.surface_ids()))


def shell_band(camera: Camera, planning_distance: float, cell: float) -> float:
    """How far beyond the nearest candidate distance (`planning_distance` + a safety cell) candidates are drawn
    from the surface voxel they look at, so that it stays within the camera's useful range (at least 1 m)."""
    return max(camera.useful_range - planning_distance - cell, 1.0)


CLIMB_STEPS_M = (0.5, 1.0, 1.5, 2.0, 3.0)


def climb_clear(run: TargetRun, here: ArrayLike, safe: float) -> NDArray[np.float64] | None:
    """`reconstruct` goal, when no path to a proposed view was found: the nearest point straight above `here` that
    the paths between views may start from (`is_safe`) when `here` is not one (counted in `run.climbs`); None
    when `here` is one, when none within 3 m is, or for the `map` goal. Views near the planning distance leave the
    vehicle there, and a frame that reveals more of the structure can put it under the paths' threshold."""
    if not isinstance(run.planner, ReconstructNbv):
        return None
    p = np.asarray(here, dtype=float).reshape(3)
    if is_safe(run.planner.safety, p[None], safe)[0]:
        return None
    for dz in CLIMB_STEPS_M:
        q = p - np.array([0.0, 0.0, dz])
        if is_safe(run.planner.safety, q[None], safe)[0]:
            run.climbs += 1
            return np.asarray(q, dtype=np.float64)
    return None


def camera_for(p: Explore, mission: Mission) -> Camera | None:
    """The camera an explore element plans for: the mission's stereo camera with `goal: reconstruct`, else none."""
    if p.goal != "reconstruct":
        return None
    if mission.sensors.stereo is None:
        raise ValueError("explore with `goal: reconstruct` needs `sensors.stereo`")
    return camera_of(mission.sensors.stereo)


def add_pairs(run: TargetRun | None, observation: Observation, exploring: bool) -> None:
    """Each stereo pair of a tick into the coverage record, at the tick's estimated pose (`reconstruct` only, while
    `exploring`)."""
    if run is not None and exploring and isinstance(run.planner, ReconstructNbv):
        nav = observation.nav
        for _ in observation.stereo:
            run.planner.add_pose(nav.north, nav.east, nav.depth, nav.heading)
            run.stereo_pairs += 1


def target_reached(context: AgentContext, run: TargetRun, time: float, map_target: float) -> bool:
    """Whether a run's stopping figure reached its target: `goal: map`, the map's own completeness estimate
    (`run.estimate`) against `map_target`; `goal: reconstruct`, the stereo coverage record brought up to date and
    logged (`explore_stereo_coverage`), its share seen well times how far the object is bounded
    (`TargetRun.bounded`) against `STEREO_TARGET`."""
    if not isinstance(run.planner, ReconstructNbv):
        return run.estimate >= map_target
    share = run.stereo_share = run.planner.stereo_share()
    context.emit("explore_stereo_coverage", time, element=context.element.id, object=run.target.id,
                 view=len(run.views), pairs=run.stereo_pairs, share_percent=round(100.0 * share, 1),
                 bounded=round(run.bounded(), 2))
    return run.bounded() * share >= STEREO_TARGET


def stereo_figures(runs: list[TargetRun], context: AgentContext, goal: str) -> dict[str, Any]:
    """The element's stereo figures for `metrics.json` when its stereo camera records or plans: the goal, the
    camera as the truth's stereo coverage scores it (`mission.sim.stereo_coverage`), and the own estimate."""
    stereo = context.mission.sensors.stereo
    if stereo is None or (goal != "reconstruct" and not {"model", "record"} & set(context.element.actions)):
        return {}
    camera = camera_of(stereo)
    out: dict[str, Any] = {"goal": goal, "stereo_camera": {
        "fov_deg": [round(a, 3) for a in camera.fov_deg], "useful_range_m": camera.useful_range,
        "min_range_m": camera.min_range}}
    shares = [r.stereo_share for r in runs if r.stereo_share is not None]
    if shares:
        out["stereo_coverage_estimate_percent"] = round(100.0 * float(np.mean(shares)), 1)
    return out
