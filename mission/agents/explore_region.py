"""What an explore element scans and what it knows before it starts (seed 002 §2.2.2: "the start point and the
safe trajectory around the object can be determined from the occupancy and information maps obtained before").

* `targets`: the objects an `explore.object` names — every detected object the database lacks (`detected`), or
  a database object by id — each as a `Target` (estimated centre, footprint radius, top and bottom depths);
* `exploration_box`: the box around a target the view planner works in;
* `prior_map`: a voxel map seeded from the survey's height map (`Knowledge.maps`, estimated frame): the water
  column above each sounding free, the sounding occupied — what the multibeam saw from above;
* `survey_map_for`: the survey products whose grid covers a target.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mission.agents.survey import charted_centre
from mission.knowledge import Knowledge
from mission.language.models import Mission
from planners.occupancy import VoxelMap

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Target:
    """An object to scan, in the estimated frame (NED metres)."""

    id: str
    north: float
    east: float
    radius: float
    """Half the footprint's diagonal."""
    top_depth: float
    bottom_depth: float
    """The seabed under it (top + height)."""
    length: float
    width: float
    heading_deg: float
    source: str  # "detected" | "database"

    @property
    def centre(self) -> Array:
        return np.array([self.north, self.east, 0.5 * (self.top_depth + self.bottom_depth)])


def targets(name: str, mission: Mission, knowledge: Knowledge) -> list[Target]:
    """The targets `explore.object: name` designates (empty when there are none)."""
    if name == "detected":
        return [Target(d.id, d.north, d.east, 0.5 * math.hypot(d.length, d.width), d.depth, d.depth + d.height,
                       d.length, d.width, d.heading_deg, "detected") for d in knowledge.unknown_objects()]
    found = [d for d in knowledge.detections if d.database_id == name]
    if found:  # the survey saw it: its estimate beats the chart
        d = found[-1]
        return [Target(name, d.north, d.east, 0.5 * math.hypot(d.length, d.width), d.depth, d.depth + d.height,
                       d.length, d.width, d.heading_deg, "detected")]
    obj = next((o for o in mission.objects if o.id == name), None)
    if obj is None:
        return []
    n, e = charted_centre(obj)
    length, width, height = obj.size
    return [Target(name, n, e, 0.5 * math.hypot(length, width), obj.pose.depth - height, obj.pose.depth,
                   length, width, obj.pose.heading, "database")]


def exploration_box(target: Target, safe_distance: float, max_range: float, margin: float = 6.0,
                    ceiling: float | None = None) -> tuple[Array, Array]:
    """(lo, hi) of the box the planner explores: the target with room for views on a shell `safe_distance` to
    `safe_distance + max_range/2` from it, from `ceiling` (the depth the vehicle arrives at, when shallower)
    down to just under the seabed."""
    half = target.radius + safe_distance + margin
    up = safe_distance + 0.5 * max_range + 1.5
    top = target.top_depth - up if ceiling is None else min(target.top_depth - up, ceiling)
    lo = np.array([target.north - half, target.east - half, top])
    hi = np.array([target.north + half, target.east + half, target.bottom_depth + 1.5])
    return lo, hi


def survey_map_for(knowledge: Knowledge, target: Target) -> dict[str, Any] | None:
    """The latest survey height map whose grid holds the target's centre."""
    for products in reversed(list(knowledge.maps.values())):
        if "depth" not in products:
            continue
        depth = np.asarray(products["depth"])
        cell, n0, e0 = float(products["cell"]), float(products["north0"]), float(products["east0"])
        i = int(round((target.north - n0) / cell))
        j = int(round((target.east - e0) / cell))
        if 0 <= i < depth.shape[0] and 0 <= j < depth.shape[1]:
            found: dict[str, Any] = products
            return found
    return None


def prior_map(products: dict[str, Any] | None, lo: Array, hi: Array, resolution: float,
              uncertain: float = 0.0) -> VoxelMap:
    """A voxel map over [lo, hi]: for every voxel column with a sounding, free from the box's top down to the
    sounding and occupied there — one miss and one hit, exactly what a vertical beam inserted with
    `VoxelMap.insert_scan` gives (unknown where the survey has no sounding, or without a survey). Written in one
    vectorised update instead of one beam per column.

    With `uncertain` > 0 the last `uncertain` metres above each sounding stay unknown and nothing is marked
    occupied: a sounding is the mean of a grid cell (§2.1), so near an object's edges it says little about where
    the surface is; the scanner has to find it."""
    vm = VoxelMap(resolution)
    if products is None:
        return vm
    depth = fill_holes(np.asarray(products["depth"], dtype=float))
    cell, n0, e0 = float(products["cell"]), float(products["north0"]), float(products["east0"])
    k_lo = np.floor(np.asarray(lo, dtype=float) / resolution).astype(np.int64)
    k_hi = np.ceil(np.asarray(hi, dtype=float) / resolution).astype(np.int64)
    ki, kj = np.arange(k_lo[0], k_hi[0]), np.arange(k_lo[1], k_hi[1])
    ii = np.rint(((ki + 0.5) * resolution - n0) / cell).astype(np.int64)
    jj = np.rint(((kj + 0.5) * resolution - e0) / cell).astype(np.int64)
    on = (ii[:, None] >= 0) & (ii[:, None] < depth.shape[0]) & (jj[None, :] >= 0) & (jj[None, :] < depth.shape[1])
    sounding = np.full(on.shape, np.nan)
    sounding[on] = depth[np.clip(ii, 0, depth.shape[0] - 1)[:, None].repeat(len(jj), 1)[on],
                         np.clip(jj, 0, depth.shape[1] - 1)[None, :].repeat(len(ii), 0)[on]]
    ci, cj = np.nonzero(np.isfinite(sounding) & (sounding > lo[2]))
    if not len(ci):
        return vm
    end_k = np.floor(sounding[ci, cj] / resolution).astype(np.int64)  # the voxel each sounding lies in
    kz = np.arange(k_lo[2], int(end_k.max()) + 1)
    free = kz[None, :] < end_k[:, None]
    if uncertain > 0.0:
        free = kz[None, :] < np.floor((sounding[ci, cj] - uncertain) / resolution)[:, None]
    col, lev = np.nonzero(free)
    keys_free = np.stack([ki[ci[col]], kj[cj[col]], kz[lev]], axis=1)
    keys_hit = np.stack([ki[ci], kj[cj], end_k], axis=1)
    store, codec = vm.store, vm.codec
    store.cover(np.minimum(keys_free.min(axis=0), keys_hit.min(axis=0)),
                np.maximum(keys_free.max(axis=0), keys_hit.max(axis=0)))
    updates = [(keys_free, codec.after_miss)] + ([(keys_hit, codec.after_hit)] if uncertain <= 0.0 else [])
    for keys, table in updates:
        rel = (keys - store.origin_key).astype(np.int32).T.copy()
        at = store.positions((rel[0], rel[1], rel[2]), allocate=True)
        store.pool[at] = table.take(store.pool.take(at))
    return vm


def fill_holes(depth: Array, passes: int = 2) -> Array:
    """Cells without a sounding (holes between the beams at the swath's edge) take the shallowest sounding among
    their 8 neighbours: the surface can be that high there, so the free space carved above it stays free. A hole
    left would be an unknown pillar from the surface down, which the safety grid rightly treats as an obstacle."""
    from scipy import ndimage

    out = depth.copy()
    for _ in range(passes):
        hole = ~np.isfinite(out)
        if not hole.any():
            break
        shallowest = ndimage.minimum_filter(np.where(hole, np.inf, out), size=3, mode="nearest")
        out[hole] = np.where(np.isfinite(shallowest[hole]), shallowest[hole], np.nan)
    return out


def seabed_depth(products: dict[str, Any] | None, target: Target, radius: float) -> float:
    """The deepest sounding within `radius` of the target (its bottom depth without a survey)."""
    if products is None:
        return target.bottom_depth
    depth = np.asarray(products["depth"], dtype=float)
    cell, n0, e0 = float(products["cell"]), float(products["north0"]), float(products["east0"])
    i0, i1 = int((target.north - radius - n0) / cell), int((target.north + radius - n0) / cell) + 1
    j0, j1 = int((target.east - radius - e0) / cell), int((target.east + radius - e0) / cell) + 1
    window = depth[max(i0, 0):max(i1, 0), max(j0, 0):max(j1, 0)]
    return float(np.nanmax(window)) if window.size and np.isfinite(window).any() else target.bottom_depth


def seabed_plane(products: dict[str, Any] | None, target: Target, fallback: float,
                 ring: tuple[float, float] = (1.0, 5.0)) -> tuple[float, float, float]:
    """The seabed under a target as a plane, depth = a + b·north + c·east (estimated frame), least-squares fitted
    to the soundings in a ring `ring` metres beyond its footprint's circle (the object itself hides the seabed
    under it); flat at `fallback` without a survey or with too few soundings.

    >>> nn, ee = np.meshgrid(np.arange(40) * 0.5, np.arange(40) * 0.5, indexing="ij")
    >>> depth = 50.0 + 0.01 * nn - 0.02 * ee
    >>> t = Target("x", 10.0, 10.0, 2.0, 47.0, 50.0, 2.0, 2.0, 0.0, "detected")
    >>> [round(v, 4) for v in seabed_plane({"depth": depth, "cell": 0.5, "north0": 0.0, "east0": 0.0}, t, 0.0)]
    [50.0, 0.01, -0.02]
    """
    if products is None:
        return fallback, 0.0, 0.0
    depth = np.asarray(products["depth"], dtype=float)
    cell, n0, e0 = float(products["cell"]), float(products["north0"]), float(products["east0"])
    nn = np.broadcast_to(n0 + np.arange(depth.shape[0])[:, None] * cell, depth.shape)
    ee = np.broadcast_to(e0 + np.arange(depth.shape[1])[None, :] * cell, depth.shape)
    r = np.hypot(nn - target.north, ee - target.east)
    use = np.isfinite(depth) & (r >= target.radius + ring[0]) & (r <= target.radius + ring[1])
    if use.sum() < 12:
        return fallback, 0.0, 0.0
    a = np.column_stack([np.ones(int(use.sum())), nn[use], ee[use]])
    coef = np.linalg.lstsq(a, depth[use], rcond=None)[0]
    return float(coef[0]), float(coef[1]), float(coef[2])
