"""Next-best-view scanning of one object (seed 002 §2.2.2) for the `explore` agent: the planner for a scanner
fixed to the hull, the object's region that the frontier and contour terms count, scanner frames as the planner
takes them, and the record of one object's exploration (`TargetRun`) with the map's own estimate of how much of
the object's surface it has observed (`planners.nbv.completeness` over the object's region above the seabed)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from mission.agents.explore_region import (
    Target,
    exploration_box,
    prior_map,
    seabed_depth,
    seabed_plane,
    survey_map_for,
)
from mission.agents.report import ExploredObject
from mission.frames import rotation_zyx
from mission.knowledge import Knowledge
from mission.vehicle import ScanFrame
from planners.nbv import (
    FREE,
    OCCUPIED,
    UNKNOWN,
    Camera,
    NbvPlanner,
    Scan,
    Scanner,
    StateGrid,
    View,
    Views,
    Weights,
    is_safe_view,
    segment_safe,
    surface_completeness,
)

FOCUS_MARGIN_M = 1.5  # the object's region: its footprint's circle and its height grown by this much
RESOLUTION_M = 0.25
PRIOR_UNCERTAIN_M = 0.5  # the survey's soundings are 0.5 m cell means: the last 0.5 m above them stays unknown
MIN_UNKNOWN = 4  # a view that would reveal fewer unknown voxels of the object's region is not worth the move
SHORTLIST = 60
"""Candidates cast with every planning ray after the sparse pre-screen (`NbvPlanner.shortlist`)."""
SEABED_BAND_M = 0.3
"""Voxels whose centre lies within this of the seabed (the survey's plane under the object) belong to the seabed
for the completeness estimate: the seabed's own returns and shadows are not the object's surface ..."""
FOOT_BAND_M = 0.1
"""... except, from this height up, in the columns at the object's foot (next to a column of the object's mapped
shell): there the band holds the bottom strip of its sides, which the truth counts down to 0.1 m ..."""
MIN_SIDES = 3
"""The completeness estimate counts in full once views have looked at the object from this many of the four
quarters around it (north-east, south-east, …): before the object is bounded from several sides, the unknown behind
what one view saw can sit enclosed by the shell and the region's edge and pass for a finished surface (a campaign
of the reference mission stopped after one view at 11 m with 1 % of the surface observed and an estimate of 100 %)."""
MIN_SHELL = 0.3
"""... and once the occupied shell holds this share of the voxels that the detection's box would show (its top and
four sides at the map's resolution)."""
UNDER_PLANE_M = 0.15
"""... and, over the object's detected footprint (grown by a voxel), down to this depth below the plane: a low
part there (a base frame a few decimetres high) is the object's surface, with its unknown inside beneath it, not
seabed, and the seabed under a footprint departs from the plane fitted around it by this much."""


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


def surface_region(grid: StateGrid, focus: np.ndarray, plane: tuple[float, float, float],
                   target: Target) -> tuple[np.ndarray, np.ndarray]:
    """The object's region (`focus`) above the seabed plane depth = a + b·north + c·east: the voxels whose centre
    lies more than `SEABED_BAND_M` above it or, over the target's footprint, above `UNDER_PLANE_M` below it; and
    the band from `FOOT_BAND_M` to `SEABED_BAND_M` above it (counted at the object's foot: `TargetRun`)."""
    ijk = np.indices(grid.shape).reshape(3, -1).T
    c = grid.centres(ijk)
    height = (plane[0] + plane[1] * c[:, 0] + plane[2] * c[:, 1] - c[:, 2]).reshape(grid.shape)
    a = math.radians(target.heading_deg)
    along = (c[:, 0] - target.north) * math.cos(a) + (c[:, 1] - target.east) * math.sin(a)
    across = -(c[:, 0] - target.north) * math.sin(a) + (c[:, 1] - target.east) * math.cos(a)
    inside = ((np.abs(along) <= 0.5 * target.length + grid.resolution)
              & (np.abs(across) <= 0.5 * target.width + grid.resolution)).reshape(grid.shape)
    region = focus & ((height > SEABED_BAND_M) | (inside & (height > -UNDER_PLANE_M)))
    return np.asarray(region), np.asarray(focus & ~region & (height > FOOT_BAND_M) & (height <= SEABED_BAND_M))


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
    iterations_cpu_ms: list[float] = field(default_factory=list)
    """CPU time of each iteration (completeness estimate + propose + connect): the machine may be shared, and wall
    time then says more about the load than about the planner."""
    integrate_ms: list[float] = field(default_factory=list)
    volume: list[tuple[float, float, float]] = field(default_factory=list)  # time, known m³, coverage estimate
    rejected: int = 0
    replans: int = 0
    stop_reason: str = ""
    estimate: float = 0.0
    focus_done_at: float | None = None
    """When the object's region had nothing left to reveal (then the whole box is explored)."""

    region: np.ndarray | None = None
    """The object's region above the seabed, where the completeness estimate counts (None: none yet)."""
    foot: np.ndarray | None = None
    """The band just above the seabed, counted in the columns at the object's foot (`FOOT_BAND_M`)."""
    stereo_share: float | None = None
    """`reconstruct` goal: the share of the object's mapped surface the stereo camera has seen well."""
    stereo_pairs: int = 0
    climbs: int = 0
    """`reconstruct` goal: climbs clear of a position no path left from (`explore_stereo.climb_clear`)."""

    def object_voxels(self) -> np.ndarray:
        """Flat grid ids of the occupied voxels of the object's region above the seabed."""
        grid = self.planner.grid
        if self.region is None:
            return np.zeros(0, dtype=np.int64)
        return np.asarray(grid.occupied_ids[self.region.reshape(-1)[grid.occupied_ids]])

    def sides_seen(self) -> int:
        """How many of the four quarters around the object (by bearing from its centre) views were taken from."""
        t = self.target
        return len({int((math.degrees(math.atan2(e - t.east, n - t.north)) % 360.0) // 90.0)
                    for _, n, e, _, _ in self.views})

    def expected_voxels(self) -> float:
        """Surface voxels the detection's box would have: its top and four sides."""
        t, res = self.target, self.planner.grid.resolution
        height = max(self.seabed - t.top_depth, 0.0)
        return (t.length * t.width + 2.0 * (t.length + t.width) * height) / res**2

    def bounded(self) -> float:
        """How far the object is bounded, 0–1: the sides seen against `MIN_SIDES`, times the shell mapped against
        `MIN_SHELL` of the detection's box (each capped at 1)."""
        sides = min(1.0, self.sides_seen() / MIN_SIDES)
        shell = min(1.0, len(self.object_voxels()) / max(MIN_SHELL * self.expected_voxels(), 1.0))
        return sides * shell

    def coverage_estimate(self) -> float:
        """The map's own estimate of the share of the object's surface observed (`planners.nbv.completeness`):
        the voxels its beams ended in against the frontier of the unknown space joined to them, within the
        object's region (and the band at its foot), scaled by how far the object is bounded (`bounded`)."""
        if self.region is None:
            return 0.0
        bounded = self.bounded()
        if bounded <= 0.0:
            return 0.0
        states = self.planner.grid.states
        region = self.region
        if self.foot is not None:
            shell = ((states == OCCUPIED) & region).any(axis=2)
            near = shell.copy()  # the shell's columns and their 8 neighbours
            for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (1, -1), (-1, 1), (-1, -1)):
                near |= np.roll(np.roll(shell, di, axis=0), dj, axis=1)
            region = region | (self.foot & near[:, :, None])
        return bounded * surface_completeness(states, region, self.planner.returns).fraction


def start_view(planner: FixedMountNbv, target: Target, seabed: float, here: tuple[float, float], safe: float,
               tilt_deg: float) -> View | None:
    """A safe, known-free view facing the object, on the vehicle's side of it (`here`: north, east), as near the
    ideal as found: `safe` plus 2–5 m from the object's circle, 1.5–4.5 m above the seabed's safe depth."""
    bearing = math.atan2(here[1] - target.east, here[0] - target.north)
    depth0 = seabed - safe - 1.5
    for dr in (2.0, 3.0, 4.0, 5.0):
        for dd in (0.0, -1.0, -2.0, -3.0):
            for da in np.radians([0, 20, -20, 40, -40, 60, -60, 90, -90, 120, -120, 150, -150, 180]):
                r = target.radius + safe + dr
                p = np.array([target.north + r * math.cos(bearing + da), target.east + r * math.sin(bearing + da),
                              depth0 + dd])
                if planner.grid.state(p[None])[0] == FREE and is_safe_view(planner.safety, p[None], safe)[0]:
                    heading = math.degrees(math.atan2(target.east - p[1], target.north - p[0])) % 360.0
                    return View.at(p, heading, -tilt_deg)
    return None


def target_run(target: Target, knowledge: Knowledge, model: Scanner, weights: Weights, safe: float, ceiling: float,
               seed: int, here: tuple[float, float], tilt_deg: float, camera: Camera | None = None) -> TargetRun:
    """The exploration of one object: its box (no shallower than `ceiling`), a planner over a voxel map seeded
    from the survey's height map (with `camera`, the `reconstruct` goal's `explore_stereo.ReconstructNbv`), and a
    start view; without one, the run's `stop_reason` says so."""
    lo, hi = exploration_box(target, safe, model.max_range, ceiling=ceiling)
    products = survey_map_for(knowledge, target)
    vm = prior_map(products, lo, hi, RESOLUTION_M, uncertain=PRIOR_UNCERTAIN_M)
    seabed = seabed_depth(products, target, target.radius + 1.0)
    if camera is None:
        planner = FixedMountNbv(vm, lo, hi, model, weights=weights, safe_distance=safe, seed=seed)
    else:
        from mission.agents.explore_stereo import ReconstructNbv, shell_band  # it builds on this module

        planner = ReconstructNbv(vm, lo, hi, model, weights=weights, safe_distance=safe, seed=seed, camera=camera)
        planner.band = shell_band(camera, safe, planner.safety.cell)
    planner.focus = object_region(planner.grid, target, seabed)
    planner.min_unknown = MIN_UNKNOWN  # the object's region alone holds few unknown voxels a view can reach
    planner.shortlist = SHORTLIST
    region, foot = surface_region(planner.grid, planner.focus, seabed_plane(products, target, seabed), target)
    if camera is not None:
        planner.region = region  # type: ignore[attr-defined]
    start = start_view(planner, target, seabed, here, safe, tilt_deg)
    if start is None:
        return TargetRun(target, planner, lo, hi, seabed, View.at(target.centre), stop_reason="no safe starting view",
                         region=region, foot=foot)
    return TargetRun(target, planner, lo, hi, seabed, start, region=region, foot=foot)


def path_safe(planner: NbvPlanner, points: np.ndarray, safe: float) -> bool:
    """Whether every segment of a path (points, N×3) keeps `safe` metres from what the planner's map holds."""
    return all(segment_safe(planner.safety, a, b, safe) for a, b in zip(points[:-1], points[1:], strict=True))


def iteration_figures(runs: list[TargetRun]) -> dict[str, dict[str, float | None]]:
    """Mean and max wall and CPU time of the runs' iterations (completeness estimate + propose + connect)."""
    out: dict[str, dict[str, float | None]] = {}
    for key, times in (("iteration_time_ms", [t for r in runs for t in r.iterations_ms]),
                       ("iteration_cpu_ms", [t for r in runs for t in r.iterations_cpu_ms])):
        out[key] = {"mean": round(float(np.mean(times)), 1) if times else None,
                    "max": round(float(np.max(times)), 1) if times else None}
    return out


def nbv_results(runs: list[TargetRun], t0: float) -> tuple[list[ExploredObject], dict[str, np.ndarray]]:
    """Each explored object's figures, and the products of the run folder: the occupied voxels, views, known
    volume over time and exploration boxes of all runs (a last column says which run)."""
    occupied: list[np.ndarray] = []
    views: list[tuple[float, ...]] = []
    volume: list[tuple[float, ...]] = []
    boxes: list[list[float]] = []
    objects: list[ExploredObject] = []
    for k, run in enumerate(runs):
        grid = run.planner.grid
        ids = grid.occupied_ids
        centres = grid.centres(np.stack(np.unravel_index(ids, grid.shape), axis=1))
        occupied.append(np.column_stack([centres, np.full(len(centres), k)]))
        views.extend((*v, k) for v in run.views)
        volume.extend((*v, k) for v in run.volume)
        boxes.append([*run.lo, *run.hi])
        it = run.iterations_ms
        run.estimate = run.coverage_estimate() if run.stop_reason != "no safe starting view" else 0.0
        objects.append(ExploredObject(run.target.id, run.target.source, round(run.target.north, 2),
                                      round(run.target.east, 2), {
            "views": len(run.views),
            "stop_reason": run.stop_reason or "element ended",
            "object_region_done_s": None if run.focus_done_at is None else round(run.focus_done_at - t0, 1),
            "coverage_estimate_percent": round(100.0 * run.estimate, 1),
            "rejected_views": run.rejected, "replans": run.replans,
            "iteration_time_ms": {"mean": round(float(np.mean(it)), 1) if it else None,
                                  "max": round(float(np.max(it)), 1) if it else None},
            "scan_integration_ms": round(float(np.mean(run.integrate_ms)), 1) if run.integrate_ms else None,
            "object_voxels_mapped": int(len(run.object_voxels())),
            **({} if run.stereo_share is None else {
                "stereo_coverage_estimate_percent": round(100.0 * run.stereo_share, 1),
                "stereo_pairs_planned_with": run.stereo_pairs, "climbs": run.climbs})}))
    products = {
        "explore_occupied": np.concatenate(occupied).astype(np.float32) if occupied else np.zeros((0, 4)),
        "explore_views": np.asarray(views, dtype=np.float64).reshape(-1, 6),
        "explore_volume": np.asarray(volume, dtype=np.float64).reshape(-1, 4),
        "explore_boxes": np.asarray(boxes, dtype=np.float64).reshape(-1, 6)}
    return objects, products
