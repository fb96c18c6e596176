"""Metrics of an explore element against the truth the simulator kept (seed 002 §2.2).

For each object the agent explored, matched to the true object it is (the nearest within `MATCH_RADIUS_M`):

* `surface_observed_percent`: the share of the object's TRUE surface voxels (voxels of the agent's resolution
  holding a patch of a part's exposed surface, sampled at a third of a voxel: neither inside another part nor
  within `CONTACT_M` of the seabed or below it — where a part meets the seabed no sensor sees it) in which a
  scanner ray truly ended: the simulator logs, for every frame, the exact surface points its rays hit on
  objects, cast from the true pose. This is what the sensor observed, whatever the navigation error;
* `map_surface_percent`: the share of the same true surface voxels next to (within one voxel of) a voxel the
  agent's own map holds occupied. The map is built at the estimated poses, so this also pays for navigation
  error between views; the gap between the two figures is that price;
* `min_distance_to_object_m`: the closest approach of the TRUE trajectory during the element to the object's TRUE
  geometry (exact distance to the boxes and cylinders), and `safe_distance_breached` when it is below the
  element's `safe_distance`; `min_distance_to_seabed_m` likewise (true depth against the true seabed under the
  vehicle);
* the element's `path_length_m` is the true 3-D path length (the vehicle moves vertically between views).

With a stereo camera recording (`model`, `record`, or `goal: reconstruct`), `stereo_coverage_true_percent`: the
share of the object's true surface the recorded pairs saw within the useful range and at ≤ 60° incidence, from
the true camera poses (`mission.sim.stereo_coverage`), and `stereo_pairs`.

For photo surveys, `photo_coverage_percent` is the agent's (footprints at the estimated poses over the estimated
object area); `photo_coverage_true_percent` places the same photographs at the true poses over the true object.
"""

from __future__ import annotations

import copy
import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mission.agents.report import ExploredObject, ExploreReport
from mission.executive import ElementReport
from mission.frames import rotation_zyx
from mission.knowledge import Knowledge
from mission.sim.vehicle import SimulatedVehicle
from mission.world.model import Box, Cylinder, Part
from mission.world.scene import PlacedObject, Scene

Array = NDArray[np.float64]
MATCH_RADIUS_M = 5.0
CONTACT_M = 0.1
"""Surface this close above the seabed is in contact with it (the seabed model is a 1 m grid with ~0.25 m of
roughness; sediment fills such gaps), so it is not counted as exposed."""
_AXIS = {"x": rotation_zyx(0.0, 90.0, 0.0), "y": rotation_zyx(0.0, 0.0, -90.0), "z": np.eye(3)}


def part_frame(obj: PlacedObject, part: Part) -> tuple[Array, Array]:
    """(R_world_part, centre in the world) of a part; a cylinder's local z is its axis."""
    T = obj.T_world_object
    R_object_part = rotation_zyx(part.heading) if isinstance(part, Box) else _AXIS[part.axis]
    return T[:3, :3] @ R_object_part, T[:3, :3] @ np.asarray(part.at, dtype=np.float64) + T[:3, 3]


def _grid(a: float, b: float, spacing: float) -> Array:
    """Midpoints of equal steps ≤ `spacing` across [a, b]: a face's samples stay half a step inside its edges, so
    a voxel counts as holding surface when a patch of the face lies in it, not when only an edge touches its
    boundary (a face ending exactly on a voxel plane would otherwise add a layer of voxels no ray can end in)."""
    n = max(1, math.ceil((b - a) / spacing))
    return np.asarray(a + (np.arange(n, dtype=np.float64) + 0.5) * ((b - a) / n), dtype=np.float64)


def local_samples(part: Part, spacing: float) -> tuple[Array, Array]:
    """Surface points and outward normals of a part in its own frame (centred; a cylinder along z)."""
    points, normals = [], []
    if isinstance(part, Box):
        half = 0.5 * np.asarray(part.size, dtype=np.float64)
        for axis in range(3):
            u, v = [a for a in range(3) if a != axis]
            uu, vv = np.meshgrid(_grid(-half[u], half[u], spacing), _grid(-half[v], half[v], spacing), indexing="ij")
            for sign in (-1.0, 1.0):
                face = np.zeros((uu.size, 3))
                face[:, axis], face[:, u], face[:, v] = sign * half[axis], uu.ravel(), vv.ravel()
                n = np.zeros((uu.size, 3))
                n[:, axis] = sign
                points.append(face)
                normals.append(n)
        return np.concatenate(points), np.concatenate(normals)
    assert isinstance(part, Cylinder)
    r, h = part.radius, 0.5 * part.height
    angles = np.linspace(0.0, 2.0 * math.pi, max(8, math.ceil(2.0 * math.pi * r / spacing)), endpoint=False)
    aa, zz = np.meshgrid(angles, _grid(-h, h, spacing), indexing="ij")
    radial = np.stack([np.cos(aa.ravel()), np.sin(aa.ravel()), np.zeros(aa.size)], axis=1)
    points.append(radial * r + np.stack([np.zeros(aa.size), np.zeros(aa.size), zz.ravel()], axis=1))
    normals.append(radial)
    for rho in _grid(0.0, r, spacing):
        k = max(1, math.ceil(2.0 * math.pi * rho / spacing))
        a = np.linspace(0.0, 2.0 * math.pi, k, endpoint=False)
        for z in (-h, h):
            points.append(np.stack([rho * np.cos(a), rho * np.sin(a), np.full(k, z)], axis=1))
            normals.append(np.tile([0.0, 0.0, 1.0 if z > 0 else -1.0], (k, 1)))
    return np.concatenate(points), np.concatenate(normals)


def _local_surface(part: Part, spacing: float) -> Array:
    """Surface points of a part in its own frame (centred; a cylinder along z)."""
    return local_samples(part, spacing)[0]


def distance_to_part(points: Array, obj: PlacedObject, part: Part) -> Array:
    """Exact distance (m) from world points (N, 3) to a part (0 inside it)."""
    R, c = part_frame(obj, part)
    q = (np.asarray(points, dtype=np.float64).reshape(-1, 3) - c) @ R
    if isinstance(part, Box):
        gap = np.maximum(np.abs(q) - 0.5 * np.asarray(part.size, dtype=np.float64), 0.0)
        return np.asarray(np.linalg.norm(gap, axis=1))
    radial = np.maximum(np.hypot(q[:, 0], q[:, 1]) - part.radius, 0.0)
    axial = np.maximum(np.abs(q[:, 2]) - 0.5 * part.height, 0.0)
    return np.asarray(np.hypot(radial, axial))


def distance_to_object(points: Array, obj: PlacedObject) -> Array:
    return np.asarray(np.min([distance_to_part(points, obj, p.part) for p in obj.parts], axis=0))


def surface_points(obj: PlacedObject, scene: Scene, spacing: float) -> Array:
    """World points ≤ `spacing` apart on the object's exposed surface (not inside another part, not buried or in
    contact with the seabed)."""
    out = []
    for k, placed in enumerate(obj.parts):
        R, c = part_frame(obj, placed.part)
        pts = _local_surface(placed.part, spacing) @ R.T + c
        for j, other in enumerate(obj.parts):
            if j != k:
                pts = pts[distance_to_part(pts, obj, other.part) > 1e-6]
        out.append(pts)
    pts = np.concatenate(out) if out else np.zeros((0, 3))
    seabed = scene.seabed.depths_at(pts[:, 0], pts[:, 1])
    return pts[pts[:, 2] < seabed - CONTACT_M]


def surface_keys(obj: PlacedObject, scene: Scene, resolution: float) -> NDArray[np.int64]:
    """Keys floor(p / resolution) of the voxels holding some of the object's exposed surface."""
    pts = surface_points(obj, scene, resolution / 3.0)
    return np.unique(np.floor(pts / resolution).astype(np.int64), axis=0)


def _contains(keys: NDArray[np.int64], query: NDArray[np.int64]) -> NDArray[np.bool_]:
    """(M,) whether each query key is among `keys`."""
    if not len(keys) or not len(query):
        return np.zeros(len(query), dtype=bool)
    lo = np.minimum(keys.min(axis=0), query.min(axis=0))
    span = np.maximum(keys.max(axis=0), query.max(axis=0)) - lo + 1

    def flat(k: NDArray[np.int64]) -> NDArray[np.int64]:
        return np.asarray(((k[:, 0] - lo[0]) * span[1] + (k[:, 1] - lo[1])) * span[2] + (k[:, 2] - lo[2]))

    return np.isin(flat(query), flat(keys))


def _true_object(entry: ExploredObject, scene: Scene) -> PlacedObject | None:
    by_id = next((o for o in scene.objects if entry.source == "database"
                  and (o.database == entry.id or o.id == entry.id)), None)
    if by_id is not None:
        return by_id
    best = min(scene.objects, key=lambda o: math.hypot(o.footprint.centroid.y - entry.north,
                                                         o.footprint.centroid.x - entry.east), default=None)
    if best is None:
        return None
    c = best.footprint.centroid
    return best if math.hypot(c.y - entry.north, c.x - entry.east) <= MATCH_RADIUS_M else None


def _photo_truth(report: ExploreReport, item: dict[str, Any], rows: Array, scene: Scene,
                 safe_distance: float) -> None:
    """`photo_coverage_true_percent`: the true object's footprint inside the union of the photographs'
    footprints placed at the vehicle's TRUE poses (at the true depth of the object's top)."""
    from shapely import union_all

    from mission.agents.photo_survey import footprint_polygon

    fov = report.camera_fov_deg
    if not fov or not len(rows):
        return
    for explored, entry in zip(report.objects, item["objects"], strict=True):
        obj = _true_object(explored, scene)
        if obj is None:
            continue
        shapes = []
        for t in np.asarray(report.photo_times or [], dtype=np.float64):
            r = rows[int(np.argmin(np.abs(rows[:, 0] - t)))]
            altitude = obj.top_depth - r[3]
            shapes.append(footprint_polygon(r[1], r[2], r[4], 2 * altitude * math.tan(math.radians(fov[0] / 2)),
                                            2 * altitude * math.tan(math.radians(fov[1] / 2))))
        covered = union_all(shapes).intersection(obj.footprint).area / obj.footprint.area if shapes else 0.0
        entry["true_object"] = obj.id
        entry["photo_coverage_true_percent"] = round(100.0 * covered, 2)
        d = float(distance_to_object(rows[:, 1:4], obj).min())
        entry["min_distance_to_object_m"] = round(d, 3)
    shares = [e["photo_coverage_true_percent"] for e in item["objects"] if "photo_coverage_true_percent" in e]
    if shares:
        item["photo_coverage_true_percent"] = round(float(np.mean(shares)), 2)
    distances = [e["min_distance_to_object_m"] for e in item["objects"] if "min_distance_to_object_m" in e]
    if distances:
        item["min_distance_to_object_m"] = min(distances)
        item["safe_distance_breached"] = bool(min(distances) < safe_distance)


def explore_truth(report: ExploreReport, rep: ElementReport, knowledge: Knowledge, vehicle: SimulatedVehicle,
                  scene: Scene, safe_distance: float) -> dict[str, Any]:
    """An explore element's fields of `metrics.json`: the report's, with the truth-based metrics of the module
    docstring added."""
    item = copy.deepcopy(report.as_json())
    log = np.array([r[:14] for r in vehicle.log.rows], dtype=np.float64).reshape(-1, 14)
    rows: Array = log[(log[:, 0] > rep.start_time) & (log[:, 0] <= rep.end_time)]
    track = rows[:, 1:4] if len(rows) else np.zeros((0, 3))
    if len(track) > 1:
        item["path_length_m"] = round(float(np.linalg.norm(np.diff(track, axis=0), axis=1).sum()), 2)
    if len(rows):
        err = np.hypot(rows[:, 6] - rows[:, 1], rows[:, 7] - rows[:, 2])
        item["navigation_error_m"] = {"mean": round(float(err.mean()), 3), "max": round(float(err.max()), 3)}
        seabed = scene.seabed.depths_at(track[:, 0], track[:, 1])
        item["min_distance_to_seabed_m"] = round(float(np.min(seabed - track[:, 2])), 3)
    if report.planner == "rrt-photo":
        _photo_truth(report, item, rows, scene, safe_distance)
        return item
    resolution = report.resolution_m if report.resolution_m is not None else 0.25
    hits = [p for t, _, p in vehicle.log.scans if rep.start_time <= t <= rep.end_time and len(p)]
    observed = np.unique(np.floor(np.concatenate(hits) / resolution).astype(np.int64), axis=0) if hits \
        else np.zeros((0, 3), dtype=np.int64)
    products = knowledge.maps.get(rep.id, {})
    occupied = np.asarray(products.get("explore_occupied", np.zeros((0, 4))), dtype=np.float64)
    grown = np.zeros((0, 3), dtype=np.int64)
    if len(occupied):
        keys = np.floor(occupied[:, :3] / resolution).astype(np.int64)
        offsets = np.stack(np.meshgrid(*[np.arange(-1, 2)] * 3, indexing="ij"), axis=-1).reshape(-1, 3)
        grown = np.unique((keys[:, None, :] + offsets[None]).reshape(-1, 3), axis=0)
    min_distances, observed_shares, map_shares = [], [], []
    for explored, entry in zip(report.objects, item["objects"], strict=True):
        obj = _true_object(explored, scene)
        if obj is None:
            entry["true_object"] = None
            continue
        entry["true_object"] = obj.id
        truth = surface_keys(obj, scene, resolution)
        seen = _contains(observed, truth)
        mapped = _contains(grown, truth)
        entry["true_surface_voxels"] = int(len(truth))
        entry["surface_observed_percent"] = round(100.0 * float(seen.mean()), 2) if len(truth) else 0.0
        entry["map_surface_percent"] = round(100.0 * float(mapped.mean()), 2) if len(truth) else 0.0
        d = float(distance_to_object(track, obj).min()) if len(track) else math.inf
        entry["min_distance_to_object_m"] = round(d, 3)
        min_distances.append(d)
        observed_shares.append(entry["surface_observed_percent"])
        map_shares.append(entry["map_surface_percent"])
    if observed_shares:
        item["surface_observed_percent"] = round(float(np.mean(observed_shares)), 2)
        item["map_surface_percent"] = round(float(np.mean(map_shares)), 2)
    if min_distances:
        item["min_distance_to_object_m"] = round(min(min_distances), 3)
        item["safe_distance_breached"] = bool(min(min_distances) < safe_distance)
    camera = report.figures.get("stereo_camera")
    if camera is not None:
        _stereo_truth(report, item, vehicle, scene, rep, camera)
    return item


def _stereo_truth(report: ExploreReport, item: dict[str, Any], vehicle: SimulatedVehicle, scene: Scene,
                  rep: ElementReport, camera: dict[str, Any]) -> None:
    """`stereo_coverage_true_percent` per object and for the element (`mission.sim.stereo_coverage`), and
    `stereo_pairs`: the pairs the camera took during the element."""
    from mission.sim.stereo_coverage import stereo_coverage

    poses = [T for t, T in vehicle.log.frames if rep.start_time <= t <= rep.end_time]
    item["stereo_pairs"] = len(poses)
    fov = (float(camera["fov_deg"][0]), float(camera["fov_deg"][1]))
    shares = []
    for explored, entry in zip(report.objects, item["objects"], strict=True):
        obj = _true_object(explored, scene)
        if obj is None:
            continue
        share, useful = stereo_coverage(obj, scene, poses, fov, float(camera["useful_range_m"]),
                                        float(camera["min_range_m"]))
        entry["stereo_coverage_true_percent"] = round(100.0 * share, 2)
        entry["stereo_pairs_seeing_well"] = useful
        shares.append(entry["stereo_coverage_true_percent"])
    if shares:
        item["stereo_coverage_true_percent"] = round(float(np.mean(shares)), 2)
