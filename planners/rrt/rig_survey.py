"""The informative photo survey (seed 002 §2.2.1): a RIG tree over the information map, flown as Dubins curves.

The adapter between the pure RIG tree (`planners.rrt.rig`) and the world: motions are OMPL Dubins curves for the
vehicle's turning radius (`DubinsStateSpace.interpolate`, sampled every 0.5 m), each one checked against the
clearance grid at the survey depth (every sample's voxel must keep the safety distance plus a quarter metre, so
the whole curve keeps the safety distance), ending where a full turning circle is clear, and kept inside the
flight box (the area's bounding box grown by three turning radii); the information a motion reveals is the camera
footprint's (`planners.rrt.photo_gain`), with diminishing returns for cells already photographed. Photographs
are triggered along the path every along-track footprint × (1 − overlap), divided by 1 + gain·Î, as in the
lawnmower (`planners.rrt.photo`). Samples are drawn over the area's bounding box, informed samples in the area.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from planners.rrt import _ompl
from planners.rrt.clearance import ClearanceGrid
from planners.rrt.information import InformationField
from planners.rrt.photo import footprint, inside_polygon
from planners.rrt.photo_gain import Counts, PhotoModel
from planners.rrt.rig import Pose, RigSettings, Steer, plan_rig

Array = NDArray[np.float64]
SAMPLE_M = 0.5


@dataclass(frozen=True)
class InformativeSurvey:
    """An informative photo-survey plan in NED metres."""

    path: Array
    """(K, 3) north, east, depth every ≤ 0.5 m along the Dubins curves."""
    headings_deg: Array
    """(K,) heading at each path point."""
    photo_points: Array
    """(M, 3) positions where photographs are taken."""
    photo_headings_deg: Array
    footprint: tuple[float, float]
    """Camera footprint (across, along track), metres."""
    information: float
    """Σ Î·(1 − ρⁿ) the planned photographs reveal (`PhotoModel.revealed`)."""
    counts: Counts
    rounds: int
    nodes: int

    @property
    def length(self) -> float:
        return float(np.linalg.norm(np.diff(self.path, axis=0), axis=1).sum()) if len(self.path) > 1 else 0.0


def informative_survey_path(area: ArrayLike, information: InformationField, *, budget: float, altitude: float,
                            depth: float, turning_radius: float, start: ArrayLike, start_heading_deg: float,
                            fov_deg: tuple[float, float] = (60.0, 45.0), overlap: float = 0.6, gain: float = 2.0,
                            repeat: float = 0.5, coverage_floor: float = 0.0, enough: float = 0.2,
                            clearance: ClearanceGrid | None = None,
                            safety_distance: float = 0.0, iterations: int = 100, horizon: float | None = None,
                            seed: int = 0) -> InformativeSurvey:
    """A path of at most `budget` metres from `start` (north, east) photographing the polygon `area`
    ([[north, east], …]) where its information is, denser over the most informative ground.

    `repeat` is ρ of `PhotoModel` (the share of a cell's information a further photograph still reveals);
    `horizon` is the receding horizon's length (default: 8 turning radii, at least 40 m). `coverage_floor`
    raises Î inside the area to at least that value, so that blank parts of it are worth a photograph too (a
    survey that must cover the object) while informative parts stay worth several. The plan ends early once at
    most `enough` of the area's information is still unrevealed (`RigSettings.enough`). A start within the
    safety distance of an obstacle is refused (ValueError).
    """
    poly = np.asarray(area, dtype=float).reshape(-1, 2)
    if len(poly) < 3:
        raise ValueError("area needs at least three vertices")
    if not budget > 0:
        raise ValueError(f"budget must be positive, got {budget}")
    across, along = footprint(altitude, fov_deg)
    rows, cols = np.shape(information.values)
    ii, jj = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    centres = np.stack([information.north0 + ii.ravel() * information.cell,
                        information.east0 + jj.ravel() * information.cell], axis=1)
    allowed = inside_polygon(poly, centres)
    if coverage_floor > 0:
        floored = np.where(allowed.reshape(rows, cols), np.maximum(information.normalised(), coverage_floor),
                           information.normalised())
        information = InformationField(floored, information.north0, information.east0, information.cell)
    model = PhotoModel(information, across, along, repeat)
    lo, hi = poly.min(axis=0), poly.max(axis=0)
    grow = 3.0 * turning_radius
    flight = (lo[0] - grow, hi[0] + grow, lo[1] - grow, hi[1] + grow)
    steer = dubins_steer(turning_radius, depth, flight, clearance, safety_distance)
    s = np.asarray(start, dtype=float).reshape(-1)
    if clearance is not None and not clearance.safe([[s[0], s[1], depth]], safety_distance)[0]:
        raise ValueError(f"the survey's start {s.round(2).tolist()} is within {safety_distance} m of an obstacle")
    pose: Pose = (float(s[0]), float(s[1]), math.radians(start_heading_deg))
    settings = RigSettings(budget=float(budget), photo_spacing=along * (1.0 - overlap), gain=gain,
                           horizon=horizon if horizon is not None else max(40.0, 8.0 * turning_radius),
                           iterations=iterations, step=max(4.0, turning_radius),
                           near_radius=max(6.0, 1.5 * turning_radius), enough=enough,
                           turn_penalty=turning_radius, seed=seed)
    plan = plan_rig(pose, model, steer, (float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1])), settings, allowed)
    path = np.column_stack([plan.samples[:, :2], np.full(len(plan.samples), depth)])
    photos = np.column_stack([plan.photos[:, :2], np.full(len(plan.photos), depth)])
    return InformativeSurvey(path, np.degrees(plan.samples[:, 2]) % 360.0, photos,
                             np.degrees(plan.photos[:, 2]) % 360.0, (across, along), plan.information, plan.counts,
                             plan.rounds, plan.nodes)


def dubins_steer(radius: float, depth: float, box: tuple[float, float, float, float], grid: ClearanceGrid | None,
                 safety: float) -> Steer:
    """A `Steer` along OMPL Dubins curves ending headed along the bearing to the target, truncated at the
    requested length, refused when a sample leaves `box` or (with a grid) comes within `safety` of obstacles."""
    base, _, _ = _ompl.load()
    space = base.DubinsStateSpace(float(radius))
    s0, s1, s = space.allocState(), space.allocState(), space.allocState()
    # A point between two samples lies within half a sample spacing of one: its voxel keeps that much more.
    free, north0, east0, cell, cols = _free_slice(box, depth, grid, safety + SAMPLE_M / 2.0)
    rows = len(free) // cols
    inv = 1.0 / cell

    def steer(pose: Pose, north: float, east: float, max_length: float) -> Array | None:
        s0.setX(pose[0])
        s0.setY(pose[1])
        s0.setYaw(pose[2])
        s1.setX(north)
        s1.setY(east)
        s1.setYaw(math.atan2(east - pose[1], north - pose[0]))
        total = float(space.distance(s0, s1))
        if total < 1e-6:
            return None
        length = min(total, max_length)
        n = max(1, math.ceil(length / SAMPLE_M))
        out = [pose]
        for k in range(1, n + 1):
            space.interpolate(s0, s1, length * k / n / total, s)
            x, y = s.getX(), s.getY()
            i, j = math.floor((x - north0) * inv), math.floor((y - east0) * inv)
            if not (0 <= i < rows and 0 <= j < cols and free[i * cols + j]):
                return None
            out.append((x, y, s.getYaw()))
        end = out[-1]
        if not (can_circle(end, 1.0) or can_circle(end, -1.0)):
            return None  # no way on from here that stays clear: an inevitable collision state
        return np.array(out)

    ring = [(math.sin(a), 1.0 - math.cos(a)) for a in np.arange(1, 40) * (2.0 * math.pi / 39)]

    def can_circle(pose: tuple[float, float, float], side: float) -> bool:
        """Whether the full turning circle to starboard (side 1) or port (−1) from `pose` stays clear."""
        c, w = math.cos(pose[2]), math.sin(pose[2])
        for fwd, lat in ring:
            x = pose[0] + radius * (fwd * c - side * lat * w)
            y = pose[1] + radius * (fwd * w + side * lat * c)
            i, j = math.floor((x - north0) * inv), math.floor((y - east0) * inv)
            if not (0 <= i < rows and 0 <= j < cols and free[i * cols + j]):
                return False
        return True

    return steer


def _free_slice(box: tuple[float, float, float, float], depth: float, grid: ClearanceGrid | None,
                safety: float) -> tuple[list[bool], float, float, float, int]:
    """The flight box as a flat row-major list of safe cells at `depth` (the clearance grid's voxels there, or
    one cell when there is no grid) with its origin, cell size and column count; outside the grid is unsafe."""
    if grid is None:
        return [True], box[0], box[2], max(box[1] - box[0], box[3] - box[2]) + 1e-9, 1
    c = grid.cell
    i0, i1 = math.floor((box[0] - grid.origin[0]) / c), math.ceil((box[1] - grid.origin[0]) / c)
    j0, j1 = math.floor((box[2] - grid.origin[1]) / c), math.ceil((box[3] - grid.origin[1]) / c)
    ii, jj = np.meshgrid(np.arange(i0, i1), np.arange(j0, j1), indexing="ij")
    centres = np.stack([grid.origin[0] + (ii.ravel() + 0.5) * c, grid.origin[1] + (jj.ravel() + 0.5) * c,
                        np.full(ii.size, depth)], axis=1)
    inside = grid.indices(centres)[1]
    safe = grid.safe(centres, safety) & inside
    return (safe.tolist(), float(grid.origin[0] + i0 * c), float(grid.origin[1] + j0 * c), c, int(j1 - j0))
