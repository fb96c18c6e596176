"""Sonar speed: MBES pings of 512 beams over a 120° swath on the reference world, ours against a numpy ray-march.

Seed 002 §2.1 builds its maps from multibeam pings ray-cast against the world; issue 4 asks for >= 1,500 pings/s
of 512 beams on `worlds/sps_field.yaml`. Ours is `mission.sim.mbes.Multibeam` (the fan cast in C by
`mujoco.mj_multiRay` against the MuJoCo model of the scene). The anchor, implemented here, is a vectorised numpy
ray-march over the same height field (bilinear) and the same object parts (boxes and cylinders tested in their
own frames, built from the world file independently of `mission.sim.mjworld`): every beam steps 0.25 m at a time
from where it first reaches the shallowest surface under the fan, active beams only, chunks of steps at once,
objects pre-filtered by bounding box; the bracketing step is refined by bisection. Both run along the same
meander of poses at 20 m altitude across the field, in the same process; the range agreement is measured on the
poses the anchor runs plus short passes straight over each object, with a noiseless sonar.
"""

from __future__ import annotations

import math
import statistics
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mission.bench import REPO, check
from mission.frames import Array, invert, rotation_zyx
from mission.language.world import Box
from mission.world.scene import Scene

BEAMS = 512
SWATH_DEG = 120.0
MAX_RANGE = 80.0
ALTITUDE = 20.0
STEP = 0.25
CHUNK = 16
BISECTIONS = 6

Pose = tuple[float, float, float, float, float, float]


@dataclass(frozen=True)
class _Solid:
    """One object part for the ray-march: T_part_world and its extent in the part frame."""

    object_index: int
    T_part_world: Array
    half: Array  # box half sizes, or (radius, radius, half height) with the axis moved to z
    cylinder_axis: int  # −1 for a box
    lo_world: Array
    hi_world: Array


def _solids(scene: Scene) -> list[_Solid]:
    solids = []
    for k, obj in enumerate(scene.objects):
        for placed in obj.parts:
            part = placed.part
            T_object_part = np.eye(4)
            T_object_part[:3, 3] = part.at
            if isinstance(part, Box):
                T_object_part[:3, :3] = rotation_zyx(part.heading)
                half, axis = 0.5 * np.asarray(part.size, dtype=float), -1
            else:
                half, axis = np.array([part.radius, part.radius, 0.5 * part.height]), "xyz".index(part.axis)
            T_part_world = invert(obj.T_world_object @ T_object_part)
            corners = placed.corners_world
            solids.append(_Solid(k, T_part_world, half, axis, corners.min(axis=0) - 0.05,
                                 corners.max(axis=0) + 0.05))
    return solids


class RayMarch:
    """The anchor: a numpy ray-march of a beam fan against a height field and object parts."""

    def __init__(self, scene: Scene, beams: int, swath_deg: float, max_range: float, step: float = STEP) -> None:
        self.scene = scene
        self.field = scene.seabed
        self.max_range = max_range
        self.step = step
        a = np.radians(np.linspace(-0.5 * swath_deg, 0.5 * swath_deg, beams))
        self.dirs_body = np.stack([np.zeros_like(a), np.sin(a), np.cos(a)], axis=1)
        self.solids = _solids(scene)
        self.ids = np.array(["", *[o.id for o in scene.objects]])

    def _inside(self, pts: Array, want_object: bool = False) -> tuple[NDArray[np.bool_], NDArray[np.int_]]:
        """Which points lie below the seabed or inside a part; with `want_object`, which object (−1: seabed)."""
        f = self.field
        north, east = pts[:, 0], pts[:, 1]
        on_grid = (north >= f.north0) & (north <= f.north_max) & (east >= f.east0) & (east <= f.east_max)
        inside = on_grid & (pts[:, 2] >= f.depths_at(north, east))
        owner = np.full(len(pts), -1, dtype=int)
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        for s in self.solids:
            if np.any(hi < s.lo_world) or np.any(lo > s.hi_world):
                continue
            near = np.all((pts >= s.lo_world) & (pts <= s.hi_world), axis=1)
            if not near.any():
                continue
            local = pts[near] @ s.T_part_world[:3, :3].T + s.T_part_world[:3, 3]
            if s.cylinder_axis < 0:
                ok = np.all(np.abs(local) <= s.half, axis=1)
            else:
                others = [k for k in range(3) if k != s.cylinder_axis]
                radial2 = local[:, others[0]] ** 2 + local[:, others[1]] ** 2
                ok = (radial2 <= s.half[0] ** 2) & (np.abs(local[:, s.cylinder_axis]) <= s.half[2])
            idx = np.flatnonzero(near)[ok]
            inside[idx] = True
            if want_object:
                owner[idx] = s.object_index
        return inside, owner

    def _shallowest_under(self, origin: Array, reach: float) -> float:
        """Shallowest surface depth (seabed or object top) within `reach` horizontally of the origin."""
        surf = self.scene.surface
        r = surf.resolution
        i0 = max(int((origin[0] - reach - surf.north0) / r), 0)
        i1 = max(int((origin[0] + reach - surf.north0) / r) + 2, i0 + 1)
        j0 = max(int((origin[1] - reach - surf.east0) / r), 0)
        j1 = max(int((origin[1] + reach - surf.east0) / r) + 2, j0 + 1)
        block = surf.depth[i0:i1, j0:j1]
        return float(block.min()) - 0.5 if block.size else -math.inf

    def ping(self, north: float, east: float, depth: float, heading_deg: float, pitch_deg: float = 0.0,
             roll_deg: float = 0.0) -> tuple[Array, NDArray[np.str_]]:
        """Noiseless ranges (NaN: no return) and object ids ("" for seabed) of one fan."""
        origin = np.array([north, east, depth])
        dirs = self.dirs_body @ rotation_zyx(heading_deg, pitch_deg, roll_deg).T
        n = len(dirs)
        top = self._shallowest_under(origin, self.max_range)
        down = dirs[:, 2]
        start = np.where(down > 1e-9, np.maximum((top - depth) / np.where(down > 1e-9, down, 1.0), 0.0), 0.0)
        start = np.where(depth >= top, 0.0, start)
        ranges = np.full(n, np.nan)
        hi = np.full(n, np.nan)
        active = np.flatnonzero((start <= self.max_range) & ((down > 1e-9) | (depth >= top)))
        offsets = self.step * np.arange(CHUNK)
        base = start.copy()
        while active.size:
            r = base[active, None] + offsets[None, :]  # (A, CHUNK)
            pts = origin + dirs[active, None, :] * r[..., None]
            inside, _ = self._inside(pts.reshape(-1, 3))
            inside = inside.reshape(r.shape) & (r <= self.max_range)
            found = inside.any(axis=1)
            first = inside.argmax(axis=1)
            hi[active[found]] = r[found, first[found]]
            base[active] += CHUNK * self.step
            active = active[~found & (base[active] <= self.max_range)]
        hit = np.flatnonzero(~np.isnan(hi))
        lo_r = np.maximum(hi[hit] - self.step, 0.0)
        hi_r = hi[hit]
        for _ in range(BISECTIONS):
            mid = 0.5 * (lo_r + hi_r)
            inside, _ = self._inside(origin + dirs[hit] * mid[:, None])
            hi_r = np.where(inside, mid, hi_r)
            lo_r = np.where(inside, lo_r, mid)
        ranges[hit] = 0.5 * (lo_r + hi_r)
        _, owner = self._inside(origin + dirs[hit] * hi_r[:, None], want_object=True)
        ids = np.full(n, "", dtype=self.ids.dtype)
        ids[hit] = self.ids[owner + 1]
        return ranges, ids


def meander(scene: Scene, count: int) -> list[Pose]:
    """`count` poses evenly along a north–south meander at ALTITUDE over the field, with a gentle roll and pitch."""
    easts = [0.0, 55.0, 110.0, 165.0, 220.0, 275.0, 330.0]
    corners: list[tuple[float, float]] = []
    for k, e in enumerate(easts):
        corners += [(0.0, e), (350.0, e)] if k % 2 == 0 else [(350.0, e), (0.0, e)]
    seg = np.diff(np.array(corners), axis=0)
    lengths = np.hypot(seg[:, 0], seg[:, 1])
    cum = np.concatenate([[0.0], np.cumsum(lengths)])
    poses: list[Pose] = []
    for s in np.linspace(0.0, cum[-1], count, endpoint=False):
        k = int(np.searchsorted(cum, s, side="right") - 1)
        t = (s - cum[k]) / lengths[k]
        north, east = corners[k][0] + t * seg[k, 0], corners[k][1] + t * seg[k, 1]
        heading = math.degrees(math.atan2(seg[k, 1], seg[k, 0])) % 360.0
        depth = scene.surface.depth_at(north, east) - ALTITUDE
        poses.append((north, east, depth, heading, 1.0 * math.sin(s / 13.0), 2.0 * math.sin(s / 7.0)))
    return poses


def object_passes(scene: Scene, per_object: int) -> list[Pose]:
    """Short north-going passes straight over each object at ALTITUDE above its top, for the agreement on objects."""
    poses: list[Pose] = []
    for obj in scene.objects:
        centre = obj.footprint.centroid  # x = east, y = north
        for north in np.linspace(centre.y - 6.0, centre.y + 6.0, per_object):
            east = centre.x + 0.37 * math.sin(north)
            poses.append((float(north), float(east), obj.top_depth - ALTITUDE, 3.0, 0.5, -1.5))
    return poses


def _rate(fn: Any, poses: list[Pose]) -> float:
    t0 = time.perf_counter()
    for p in poses:
        fn(*p)
    return len(poses) / (time.perf_counter() - t0)


def run(quick: bool) -> tuple[dict[str, Any], dict[str, dict[str, Any]]]:
    from mission.language.loader import load_world
    from mission.sim.mbes import Multibeam
    from mission.sim.mjworld import MjWorld
    from mission.world.scene import build_scene

    world_path = REPO / "worlds" / "sps_field.yaml"
    scene = build_scene(load_world(world_path))
    t0 = time.perf_counter()
    mjw = MjWorld(scene)
    build_s = time.perf_counter() - t0
    ours = Multibeam(mjw, BEAMS, SWATH_DEG, MAX_RANGE, range_sigma=0.05, rate_hz=10.0, seed=0)
    exact = Multibeam(mjw, BEAMS, SWATH_DEG, MAX_RANGE, range_sigma=0.0, rate_hz=10.0, seed=0)
    anchor = RayMarch(scene, BEAMS, SWATH_DEG, MAX_RANGE)

    n_ours, n_anchor, repeats = (3000, 120, 3) if quick else (20000, 1000, 5)
    poses = meander(scene, n_ours)
    anchor_poses = poses[:: max(len(poses) // n_anchor, 1)][:n_anchor]
    _rate(ours.ping, poses[:50])  # warm-up
    ours_rates = [_rate(ours.ping, poses) for _ in range(repeats)]
    anchor_rate = _rate(anchor.ping, anchor_poses)
    ours_rate = statistics.median(ours_rates)

    diffs, disagree, beams_total, obj_beams, id_mismatch = [], 0, 0, 0, 0
    for p in anchor_poses + object_passes(scene, 10 if quick else 40):
        ping = exact.ping(*p)
        ref, ref_ids = anchor.ping(*p)
        both = ping.hit & ~np.isnan(ref)
        diffs.append(np.abs(ping.ranges[both] - ref[both]))
        disagree += int(np.count_nonzero(ping.hit != ~np.isnan(ref)))
        beams_total += len(ref)
        on_obj = both & ((ping.object_ids != "") | (ref_ids != ""))
        obj_beams += int(on_obj.sum())
        id_mismatch += int(np.count_nonzero(ping.object_ids[on_obj] != ref_ids[on_obj]))
    delta = np.concatenate(diffs)
    median_delta = float(np.median(delta))
    ratio = ours_rate / anchor_rate
    results = {
        "world": "worlds/sps_field.yaml",
        "beams": BEAMS, "swath_deg": SWATH_DEG, "max_range_m": MAX_RANGE, "altitude_m": ALTITUDE,
        "model_build_s": round(build_s, 4),
        "ours": {"method": "mujoco.mj_multiRay (Multibeam.ping, range noise on)", "pings": len(poses),
                 "pings_per_s": round(ours_rate, 1), "runs_pings_per_s": [round(r, 1) for r in ours_rates],
                 "us_per_beam": round(1e6 / (ours_rate * BEAMS), 3)},
        "anchor": {"method": f"numpy ray-march, step {STEP} m, chunks of {CHUNK} steps, {BISECTIONS} bisections",
                   "pings": len(anchor_poses), "pings_per_s": round(anchor_rate, 1)},
        "ratio_vs_numpy_raymarch": round(ratio, 2),
        "range_agreement": {
            "pings": len(anchor_poses), "extra_pings_over_objects": 2 * (10 if quick else 40),
            "beams_both_hit": int(delta.size),
            "median_abs_difference_m": round(median_delta, 5),
            "p95_abs_difference_m": round(float(np.percentile(delta, 95)), 5),
            "max_abs_difference_m": round(float(delta.max()), 5),
            "beams_hit_disagreement": disagree, "beams_total": beams_total,
            "beams_on_objects": obj_beams, "object_id_mismatches": id_mismatch,
        },
    }
    checks = {
        "pings_per_s": check(round(ours_rate, 1), ">= 1500"),
        "ratio_vs_numpy_raymarch": check(round(ratio, 2), ">= 3"),
        "median_range_difference_m": check(round(median_delta, 5), f"<= {STEP}"),
    }
    return results, checks
