"""Occupancy mapping: our `planners.occupancy.VoxelMap` against OctoMap (octomap-python) on the same pings.

Issue 4's goal: 512 beams over a 120° swath from 20 m altitude, 300 pings; insertion must run ≥ 2× OctoMap's
`OcTree.insertPointCloud(points, origin, maxrange=-1)` at 0.25 m and ≥ 3× at 0.1 m, with an occupied-voxel F1
against the true surface no worse than OctoMap's minus 0.01.

The pings are made here, untimed: a rough analytic seabed (~60 m deep, sloping, three scales of undulation)
with four boxes on it (a manifold, a wellhead, a pipe, a small box, some rotated); the vehicle runs north at
20 m altitude, 0.2 ± 0.03 m between pings (1.5 m/s at 7.5 Hz), swaying ±0.3 m and rolling ±2°; each beam is
ray-marched against the seabed (0.25 m steps, then bisection) and intersected exactly with the boxes, and its
range gets Gaussian noise of 2 cm + 0.1 % of range. Every beam returns (OctoMap's call has no no-return beams).

True surface voxels are the voxels the true surface passes through (per voxel column, every voxel between the
shallowest and deepest surface sample on a res/4 grid over the column, so box walls count) inside the swath
footprint (between the first and last ping, across track within the fan's reach). Each map's occupied voxels in
the footprint are scored against them; OctoMap's occupied set is read with `getLabels` at every voxel any beam
ever ended in (no other voxel can be occupied). Recall is bounded by beam density (at the swath edge the beams
land ~0.3 m apart) and is the same limit for both maps. Times are insertion only, the best of two runs.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mission.bench import check

Array = NDArray[np.float64]

BEAMS = 512
SWATH_DEG = 120.0
ALTITUDE_M = 20.0
PING_SPACING_M = 0.2
RESOLUTIONS = (0.25, 0.1)
REPEATS = 2
# (north, east, length, width, height, heading_deg): boxes standing on the seabed at their centre's depth.
BOXES = ((6.0, -9.0, 6.0, 4.0, 3.0, 30.0), (9.5, 17.0, 1.5, 1.0, 1.0, 10.0), (30.0, 10.0, 2.0, 2.0, 2.5, 0.0),
         (45.0, 0.0, 20.0, 0.8, 0.8, 75.0))


def seabed_depth(north: Array, east: Array) -> Array:
    """The bare seabed: ~60 m, sloping, with undulations of 17–23 m, 7 m and 3 m wavelength."""
    return np.asarray(60.0 + 0.01 * north - 0.015 * east
                      + 0.4 * np.sin(2 * np.pi * north / 17.0 + 0.3) * np.cos(2 * np.pi * east / 23.0)
                      + 0.25 * np.sin(2 * np.pi * (north + east) / 7.3)
                      + 0.08 * np.sin(2 * np.pi * (north - 2 * east) / 3.1))


@dataclass(frozen=True)
class Box:
    north: float
    east: float
    half_length: float
    half_width: float
    top: float
    heading: float

    def local(self, north: Array, east: Array) -> tuple[Array, Array]:
        dn, de = north - self.north, east - self.east
        c, s = math.cos(self.heading), math.sin(self.heading)
        return dn * c + de * s, -dn * s + de * c

    def contains(self, north: Array, east: Array) -> NDArray[np.bool_]:
        along, across = self.local(north, east)
        return np.asarray((np.abs(along) <= self.half_length) & (np.abs(across) <= self.half_width))

    def entry(self, origin: Array, directions: Array) -> Array:
        """Ray parameter (m) where each ray enters the box (a prism from `top` downwards); inf if it misses."""
        c, s = math.cos(self.heading), math.sin(self.heading)
        dn, de = origin[0] - self.north, origin[1] - self.east
        o_local = np.array([dn * c + de * s, -dn * s + de * c])
        u_local = np.stack([directions[:, 0] * c + directions[:, 1] * s,
                            -directions[:, 0] * s + directions[:, 1] * c], axis=1)
        t_in = np.zeros(len(directions))
        t_out = np.full(len(directions), np.inf)
        with np.errstate(divide="ignore", invalid="ignore"):
            for axis, half in ((0, self.half_length), (1, self.half_width)):
                u = u_local[:, axis]
                t1, t2 = (-half - o_local[axis]) / u, (half - o_local[axis]) / u
                inside = abs(o_local[axis]) <= half
                lo = np.where(u == 0, np.where(inside, -np.inf, np.inf), np.minimum(t1, t2))
                hi = np.where(u == 0, np.where(inside, np.inf, -np.inf), np.maximum(t1, t2))
                t_in, t_out = np.maximum(t_in, lo), np.minimum(t_out, hi)
            t_top = np.where(directions[:, 2] > 0, (self.top - origin[2]) / directions[:, 2], np.inf)
        t_in = np.maximum(t_in, t_top)
        return np.where(t_in <= t_out, t_in, np.inf)


def make_boxes() -> list[Box]:
    boxes = []
    for north, east, length, width, height, heading in BOXES:
        base = float(seabed_depth(np.array(north), np.array(east)))
        boxes.append(Box(north, east, length / 2, width / 2, base - height, math.radians(heading)))
    return boxes


def surface_depth(north: Array, east: Array, boxes: list[Box]) -> Array:
    """The true surface: the seabed, or a box top where a box stands."""
    depth = seabed_depth(north, east)
    for box in boxes:
        depth = np.where(box.contains(north, east), np.minimum(depth, box.top), depth)
    return depth


def cast(origin: Array, directions: Array, boxes: list[Box], max_range: float = 80.0) -> Array:
    """Range (m) along each unit direction to the first surface (seabed or box); NaN beyond `max_range`."""
    step = 0.25
    t = np.arange(0.0, max_range + step, step)
    p = origin + t[None, :, None] * directions[:, None, :]
    below = p[..., 2] >= seabed_depth(p[..., 0], p[..., 1])
    first = np.argmax(below, axis=1)
    found = below[np.arange(len(directions)), first]
    lo, hi = t[np.maximum(first - 1, 0)], t[first]
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        q = origin + mid[:, None] * directions
        under = q[:, 2] >= seabed_depth(q[:, 0], q[:, 1])
        lo, hi = np.where(under, lo, mid), np.where(under, mid, hi)
    ranges = np.where(found, hi, np.inf)
    for box in boxes:
        ranges = np.minimum(ranges, box.entry(origin, directions))
    return np.where(ranges <= max_range, ranges, np.nan)


def make_pings(count: int, seed: int = 0) -> list[tuple[Array, Array]]:
    """(origin, endpoints) of each ping, NED metres; every beam returns."""
    rng = np.random.default_rng(seed)
    boxes = make_boxes()
    angles = np.radians(np.linspace(-SWATH_DEG / 2, SWATH_DEG / 2, BEAMS))
    pings = []
    for k in range(count):
        # Speed varies a little: fans never sit exactly on voxel boundaries (where float32 OctoMap and float64
        # numpy would round a whole fan to different sides).
        north = PING_SPACING_M * k + 0.0137 + 0.03 * rng.uniform(-1.0, 1.0)
        east = 0.3 * math.sin(2 * math.pi * k / 140.0)
        depth = float(seabed_depth(np.array(north), np.array(0.0))) - ALTITUDE_M + 0.1 * math.sin(k / 23.0)
        origin = np.array([north, east, depth])
        roll = math.radians(2.0) * math.sin(2 * math.pi * k / 90.0)
        # Heading north, no pitch: the fan lies in the east–down plane, turned by the roll.
        directions = np.stack([np.zeros(BEAMS), np.sin(angles + roll), np.cos(angles + roll)], axis=1)
        ranges = cast(origin, directions, boxes)
        ranges = ranges + rng.normal(0.0, 1.0, BEAMS) * (0.02 + 0.001 * ranges)
        ok = np.isfinite(ranges)
        pings.append((origin, origin + directions[ok] * ranges[ok, None]))
    return pings


def pack(keys: NDArray[np.int64]) -> NDArray[np.int64]:
    """One int64 per voxel key (each coordinate within ±2²⁰)."""
    k = keys + (1 << 20)
    return np.asarray((k[:, 0] << 42) | (k[:, 1] << 21) | k[:, 2])


def footprint(pings: list[tuple[Array, Array]], north: Array, east: Array) -> NDArray[np.bool_]:
    """Points (north, east) between the first and last ping and across track within both neighbouring fans."""
    norths = np.array([o[0] for o, _ in pings])
    lows = np.array([e[:, 1].min() for _, e in pings])
    highs = np.array([e[:, 1].max() for _, e in pings])
    k = np.clip(np.searchsorted(norths, north), 1, len(norths) - 1)
    low, high = np.maximum(lows[k - 1], lows[k]), np.minimum(highs[k - 1], highs[k])
    return np.asarray((north >= norths[0]) & (north <= norths[-1]) & (east >= low) & (east <= high))


def true_surface(pings: list[tuple[Array, Array]], resolution: float) -> NDArray[np.int64]:
    """Packed keys of the voxels the true surface passes through, inside the swath footprint."""
    boxes = make_boxes()
    ends = np.concatenate([e for _, e in pings])
    i_range = np.arange(math.floor(pings[0][0][0] / resolution), math.floor(pings[-1][0][0] / resolution) + 1)
    j_range = np.arange(math.floor(ends[:, 1].min() / resolution), math.floor(ends[:, 1].max() / resolution) + 1)
    sub = np.arange(5) / 4.0  # samples on the column's edges and at quarters
    packed = []
    for chunk in np.array_split(i_range, max(1, len(i_range) // 40)):
        ii, jj = np.meshgrid(chunk, j_range, indexing="ij")
        ii, jj = ii.ravel(), jj.ravel()
        inside = footprint(pings, (ii + 0.5) * resolution, (jj + 0.5) * resolution)
        ii, jj = ii[inside], jj[inside]
        sn = (ii[:, None, None] + sub[None, :, None]) * resolution
        se = (jj[:, None, None] + sub[None, None, :]) * resolution
        depth = surface_depth(np.broadcast_to(sn, (len(ii), 5, 5)), np.broadcast_to(se, (len(ii), 5, 5)), boxes)
        lo = np.floor(depth.min(axis=(1, 2)) / resolution).astype(np.int64)
        hi = np.floor(depth.max(axis=(1, 2)) / resolution).astype(np.int64)
        n = hi - lo + 1
        column = np.repeat(np.arange(len(ii)), n)
        kz = np.repeat(lo, n) + np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n)
        packed.append(pack(np.stack([ii[column], jj[column], kz], axis=1)))
    return np.unique(np.concatenate(packed))


def in_footprint(pings: list[tuple[Array, Array]], keys: NDArray[np.int64], resolution: float) -> NDArray[np.int64]:
    centres = np.asarray((keys + 0.5) * resolution, dtype=float)
    return keys[footprint(pings, centres[:, 0], centres[:, 1])]


def scores(occupied: NDArray[np.int64], truth: NDArray[np.int64]) -> dict[str, float]:
    tp = int(np.isin(occupied, truth, assume_unique=True).sum())
    precision = tp / max(len(occupied), 1)
    recall = tp / max(len(truth), 1)
    f1 = 2 * precision * recall / max(precision + recall, 1e-12)
    return {"f1": round(f1, 4), "precision": round(precision, 4), "recall": round(recall, 4),
            "occupied_voxels": len(occupied)}


def run_ours(pings: list[tuple[Array, Array]], resolution: float) -> tuple[float, Any]:
    from planners.occupancy import VoxelMap

    best, kept = math.inf, None
    for _ in range(REPEATS):
        voxels = VoxelMap(resolution)
        start = time.perf_counter()
        for origin, ends in pings:
            voxels.insert_scan(origin, ends)
        elapsed = time.perf_counter() - start
        if elapsed < best:
            best, kept = elapsed, voxels
    return best, kept


def run_octomap(pings: list[tuple[Array, Array]], resolution: float) -> tuple[float, Any]:
    try:
        import octomap
    except ImportError as exc:  # pragma: no cover - a bench extra
        raise ImportError("the mapping benchmark needs octomap-python: pip install -e '.[bench]'") from exc
    best, kept = math.inf, None
    for _ in range(REPEATS):
        tree = octomap.OcTree(resolution)
        start = time.perf_counter()
        for origin, ends in pings:
            tree.insertPointCloud(ends, origin, maxrange=-1.0)
        elapsed = time.perf_counter() - start
        if elapsed < best:
            best, kept = elapsed, tree
        else:
            del tree
    return best, kept


def octomap_occupied(tree: Any, pings: list[tuple[Array, Array]], resolution: float) -> NDArray[np.int64]:
    """Keys of OctoMap's occupied voxels: labels at every voxel a beam ended in (float64 and float32 keys)."""
    ends = np.concatenate([e for _, e in pings])
    keys = np.concatenate([np.floor(ends / resolution), np.floor(ends.astype(np.float32) / np.float32(resolution))])
    candidates = np.unique(pack(keys.astype(np.int64)))
    k = candidates.copy()
    unpacked = np.stack([(k >> 42) & 0x1FFFFF, (k >> 21) & 0x1FFFFF, k & 0x1FFFFF], axis=1) - (1 << 20)
    labels = tree.getLabels((unpacked + 0.5) * resolution)
    return np.asarray(unpacked[np.asarray(labels) == 1], dtype=np.int64)


def run(quick: bool) -> tuple[dict[str, Any], dict[str, dict[str, Any]]]:
    count = 60 if quick else 300
    start = time.perf_counter()
    pings = make_pings(count)
    generation_s = time.perf_counter() - start
    results: dict[str, Any] = {
        "setup": {"beams": BEAMS, "swath_deg": SWATH_DEG, "altitude_m": ALTITUDE_M, "pings": count,
                  "ping_spacing_m": PING_SPACING_M, "returns": int(sum(len(e) for _, e in pings)),
                  "range_noise": "2 cm + 0.1 % of range", "boxes": len(BOXES), "repeats": REPEATS,
                  "ping_generation_s": round(generation_s, 2)},
    }
    checks: dict[str, dict[str, Any]] = {}
    for resolution in RESOLUTIONS:
        truth = true_surface(pings, resolution)
        ours_s, voxels = run_ours(pings, resolution)
        octo_s, tree = run_octomap(pings, resolution)
        ours = scores(np.unique(pack(in_footprint(pings, voxels.occupied_keys(), resolution))), truth)
        octo = scores(np.unique(pack(in_footprint(pings, octomap_occupied(tree, pings, resolution), resolution))),
                      truth)
        ours.update(pings_per_s=round(count / ours_s, 1), insert_s=round(ours_s, 3),
                    memory_mb=round(voxels.memory_bytes / 1e6, 1))
        octo.update(pings_per_s=round(count / octo_s, 1), insert_s=round(octo_s, 3),
                    memory_mb=round(tree.memoryUsage() / 1e6, 1))
        ratio = octo_s / ours_s
        name = f"{resolution:g}m"
        results[name] = {"true_surface_voxels": len(truth), "ours": ours, "octomap": octo,
                         "pings_per_s_ratio": round(ratio, 2), "f1_delta": round(ours["f1"] - octo["f1"], 4)}
        checks[f"pings_per_s_ratio_{name}"] = check(round(ratio, 2), ">= 2" if resolution >= 0.25 else ">= 3")
        checks[f"f1_delta_{name}"] = check(round(ours["f1"] - octo["f1"], 4), ">= -0.01")
        del tree, voxels
    return results, checks
