"""`auv reconstruct`: a 3D model of an explored object from a run folder's stereo recording (issue 22; seed 003
"3D reconstruction", seed 002's exploration deliverable).

The recording is a KITTI-layout folder (`mission.sim.stereo_record`): `image_0/NNNNNN.png`, `image_1/NNNNNN.png`
(8-bit grey, left and right, rectified), `calib.txt` (`P0:`/`P1:`, 3×4 row-major; the baseline is −P1[0,3]/fx)
and the left camera's pose per pair as 12 numbers (3×4 row-major T_world_left, camera → the mission's local NED
frame; camera axes per OpenCV). The pose must be the *estimated* one: `nav.txt` when the folder has it (the
simulator's recorder writes the truth to `poses.txt` and navigation's estimate to `nav.txt`), else `poses.txt`.
The folder is looked for, in order, at RUN/models/ID, RUN/model/ID, RUN/stereo/ID, RUN/ID and RUN/stereo.

The seabed is first the plane most mesh vertices lie on; the object is the connected structure rising most above it
(`isolate_object`), and the seabed plane is refitted on a ring around it. Vertices more than `OBJECT_HEIGHT_M`
above that plane are the object, and the outputs keep it with `SEABED_MARGIN_M` of seabed around its footprint.

Outputs in the output folder (default RUN/models/ID/reconstruction): `mesh.ply` and `mesh.glb` (the cleaned mesh
with grey vertex colours, through trimesh), `points.ply` (the range maps' points, every 4th pixel, in the world
frame), `report.json` (frames, timings, mesh size, the seabed plane and the object's extent above it),
`mesh.png` (a shaded picture of the mesh), `camera_poses.txt` (the poses the range maps were fused at, KITTI's 12
numbers a line: `mission.reconstruct_poses`), `model/ID.yaml` (the multi-view model a later mission references
itself by: `mission.reconstruct_model`), and `object.yaml`: an `objects:` entry for a mission's database
(`database_entry`: pose, size and characteristic-point sets (`detected_point_sets`: points the referencing
plug-in's detector finds again and again in the close views; else corners of the mesh), the targets the designer
names, converted to the object frame, `mesh: mesh.ply`, the mesh beside it, and `model: model/ID.yaml`). A
database object's `model:` is the multi-view model file that the referencing plug-ins load as such
(`mission.plugin_settings`); the mesh, which is not one, is named by `mesh:`.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mission.errors import AuvError

Array = NDArray[np.float64]
OBJECT_HEIGHT_M = 0.1
"""Mesh vertices this far above the fitted seabed plane belong to the object."""
MATCH_WIDTH_PX = 600
"""Images are matched shrunk by the whole factor that brings them nearest this width."""
SEABED_MARGIN_M = 1.0
"""Seabed kept around the object's footprint in the outputs."""
SEARCH = ("models/{id}", "model/{id}", "stereo/{id}", "{id}", "stereo")


class ReconstructionError(AuvError):
    """A run folder holds no usable stereo recording, or the recording yields no surface."""


@dataclass(frozen=True, eq=False)
class Recording:
    folder: Path
    K: Array
    baseline: float
    poses: Array
    """(N, 4, 4) estimated T_world_left."""
    pose_file: str
    left: tuple[Path, ...]
    right: tuple[Path, ...]


def find_recording(run_dir: Path, object_id: str, element: str | None = None) -> Path:
    """The first folder of `SEARCH` under the run folder that holds a `calib.txt`; with `element`, the recording of
    that route element (RUN/stereo/ELEMENT: an explore element's `model` action names it by the element, not the
    object)."""
    if element is not None:
        folder = run_dir / "stereo" / element
        if (folder / "calib.txt").is_file():
            return folder
        raise ReconstructionError(f"{run_dir}: no stereo recording of element '{element}' (looked in stereo/{element})")
    for pattern in SEARCH:
        folder = run_dir / pattern.format(id=object_id)
        if (folder / "calib.txt").is_file():
            return folder
    tried = ", ".join(pattern.format(id=object_id) for pattern in SEARCH)
    raise ReconstructionError(f"{run_dir}: no stereo recording for '{object_id}' (looked in {tried}; "
                              "record with an explore element `actions: [model]` or `auv simulate --record-stereo`)")


def _read_poses(path: Path) -> Array:
    try:
        rows = np.atleast_2d(np.loadtxt(path, ndmin=2))
    except (OSError, ValueError) as e:
        raise ReconstructionError(f"{path}: cannot read the poses: {e}") from e
    if rows.shape[1] != 12:
        raise ReconstructionError(f"{path}: expected 12 numbers a line (3×4 row-major T_world_left), "
                                  f"got {rows.shape[1]}")
    poses = np.tile(np.eye(4), (len(rows), 1, 1))
    poses[:, :3, :4] = rows.reshape(-1, 3, 4)
    return poses


def read_recording(folder: Path) -> Recording:
    """Calibration, estimated poses and image files of a KITTI-layout folder (see the module docstring)."""
    try:
        lines = dict(line.split(":", 1) for line in (folder / "calib.txt").read_text().splitlines() if ":" in line)
        P0 = np.array(lines["P0"].split(), dtype=float).reshape(3, 4)
        P1 = np.array(lines["P1"].split(), dtype=float).reshape(3, 4)
    except (OSError, KeyError, ValueError) as e:
        raise ReconstructionError(f"{folder / 'calib.txt'}: expected lines 'P0: 12 numbers' and 'P1: ...' ({e})") from e
    K, baseline = P0[:, :3], -(P1[0, 3] - P0[0, 3]) / P0[0, 0]
    pose_file = "nav.txt" if (folder / "nav.txt").is_file() else "poses.txt"
    poses = _read_poses(folder / pose_file)
    left = tuple(sorted((folder / "image_0").glob("*.png")))
    right = tuple(sorted((folder / "image_1").glob("*.png")))
    if not (len(left) == len(right) == len(poses)) or not left:
        raise ReconstructionError(f"{folder}: image_0 ({len(left)}), image_1 ({len(right)}) and {pose_file} "
                                  f"({len(poses)}) must hold the same, non-zero, number of frames")
    return Recording(folder, K, float(baseline), poses, pose_file, left, right)


def seabed_plane(points: Array, tolerance: float = 0.05, rounds: int = 3, cell: float = 0.5,
                 rise: float = 0.15) -> Array:
    """(a, b, c) of the seabed plane depth = a·north + b·east + c. The seabed is the lowest wide surface the views
    see (objects only rise above it, and their flat tops can outnumber any one depth of a sloping, rough seabed):
    a plane is fitted to the median depth of each `cell`, the cells more than `rise` above it dropped and the fit
    repeated until none is; then least squares on the points within `tolerance` of it."""
    ij = np.floor((points[:, :2] - points[:, :2].min(axis=0)) / cell).astype(np.int64)
    keys, inverse = np.unique(ij, axis=0, return_inverse=True)
    inverse = inverse.ravel()
    order = np.lexsort((points[:, 2], inverse))
    counts = np.bincount(inverse, minlength=len(keys))
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    median_depth = points[order[starts + counts // 2], 2]  # each cell's median depth: its surface, not a stray point
    centres = points[:, :2].min(axis=0) + (keys + 0.5) * cell
    A_cells = np.column_stack([centres, np.ones(len(keys))])
    kept = np.ones(len(keys), dtype=bool)
    plane = np.array([0.0, 0.0, float(np.median(median_depth))])
    for _ in range(20):
        if kept.sum() < 3:
            break
        plane = np.linalg.lstsq(A_cells[kept], median_depth[kept], rcond=None)[0]
        now = A_cells @ plane - median_depth < rise
        if np.array_equal(now, kept):
            break
        kept = now
    z = points[:, 2]
    A = np.column_stack([points[:, 0], points[:, 1], np.ones(len(points))])
    for _ in range(rounds):
        inliers = np.abs(A @ plane - z) < tolerance
        if inliers.sum() < 3:
            break
        plane = np.linalg.lstsq(A[inliers], z[inliers], rcond=None)[0]
    return np.asarray(plane)


def isolate_object(vertices: Array, plane: Array, cell: float = 0.1, rise_m: float = 0.3, window_m: float = 8.0,
                   ring_m: float = 3.0) -> tuple[Array, Array, Array] | None:
    """The structure on the seabed: the north-east box (lo, hi) of the connected cells rising more than `rise_m`
    above the local seabed that hold the most volume, and the seabed plane refitted on the vertices in a `ring_m`
    ring around that box; None when nothing rises that high. The local seabed is the height map's grey opening by
    a `window_m` square (what is left once everything narrower than the window is shaved off): a rough seabed
    bends by more than `rise_m` across a recording, so no one plane separates it from the object."""
    import cv2

    height = plane[0] * vertices[:, 0] + plane[1] * vertices[:, 1] + plane[2] - vertices[:, 2]
    origin = vertices[:, :2].min(axis=0)
    ij = np.floor((vertices[:, :2] - origin) / cell).astype(np.int64)
    grid = np.full(tuple(int(s) for s in ij.max(axis=0) + 1), -np.inf)
    np.maximum.at(grid, (ij[:, 0], ij[:, 1]), height)
    seen = np.isfinite(grid)
    grid = np.where(seen, grid, float(height.max())).astype(np.float32)  # unseen cells never make the floor
    size = max(3, int(round(window_m / cell)) | 1)
    seabed = cv2.dilate(cv2.erode(grid, np.ones((size, size), np.uint8)), np.ones((size, size), np.uint8))
    rise = np.where(seen, grid - seabed, 0.0)
    mask = cv2.morphologyEx((rise > rise_m).astype(np.uint8), cv2.MORPH_CLOSE, np.ones((3, 3), np.uint8))
    count, labels = cv2.connectedComponents(mask, connectivity=8)
    if count <= 1:
        return None
    volume = np.bincount(labels.ravel(), weights=np.maximum(rise, 0.0).ravel(), minlength=count)
    volume[0] = 0.0
    core = labels == int(np.argmax(volume))
    # Grown by hysteresis over the cells rising a third as much (a low frame's edge), unless that spills out.
    low_mask = cv2.morphologyEx((rise > rise_m / 3).astype(np.uint8), cv2.MORPH_CLOSE, np.ones((3, 3), np.uint8))
    _, low = cv2.connectedComponents(low_mask, connectivity=8)
    grown = np.isin(low, np.unique(low[core & (low > 0)]))
    cells = np.argwhere(grown if grown.sum() <= 2 * core.sum() else core)
    lo, hi = origin + cells.min(axis=0) * cell, origin + (cells.max(axis=0) + 1) * cell

    def within(margin: float) -> NDArray[np.bool_]:
        inside = (vertices[:, :2] >= lo - margin) & (vertices[:, :2] <= hi + margin)
        return np.asarray(np.all(inside, axis=1), dtype=bool)

    ring = within(ring_m) & ~within(0.5)
    return lo, hi, (seabed_plane(vertices[ring]) if ring.sum() >= 100 else plane)


@dataclass(frozen=True)
class NamedTarget:
    """A target the designer names for the entry: `at` in the mission's local NED frame (world), photographed
    from `standoff` metres."""

    name: str
    at: tuple[float, float, float]
    standoff: float = 2.0


def parse_target(text: str) -> NamedTarget:
    """`NAME=N,E,D[:standoff]` (world NED, metres) as `auv reconstruct --target` takes it.

    >>> parse_target("valve=215.5,110.2,54.1:2.5")
    NamedTarget(name='valve', at=(215.5, 110.2, 54.1), standoff=2.5)
    """
    name, sep, rest = text.partition("=")
    coords, _, standoff = rest.partition(":")
    try:
        values = tuple(float(v) for v in coords.split(","))
        distance = float(standoff) if standoff else 2.0
    except ValueError:
        values, distance = (), 0.0
    if not sep or not name.strip() or len(values) != 3 or not distance > 0:
        raise ReconstructionError(f"target '{text}': expected NAME=NORTH,EAST,DEPTH[:STANDOFF] (metres, world "
                                  "NED; standoff > 0, default 2)")
    return NamedTarget(name.strip(), (values[0], values[1], values[2]), distance)


def database_entry(object_id: str, vertices: Array, plane: Array, targets: tuple[NamedTarget, ...] = (),
                   mesh_file: str | None = None, proposals: list[Any] | None = None) -> dict[str, Any] | None:
    """An `objects:` entry for the mission language: the object frame has its origin on the seabed plane at the
    north-west-most corner of the object's footprint box, axes north, east, down (heading 0); `size` is the box;
    the characteristic-point sets are `proposals` (`PointSetProposal`s, world frame) or else
    `propose_point_sets'` from the mesh (a symmetric set is named so in `description`);
    `targets` become the entry's targets in that frame, each referenced to the set whose centroid is nearest;
    `mesh_file` is written as the entry's `mesh:`."""
    from perception_plugins.reconstruction.keypoints import propose_point_sets

    height = plane[0] * vertices[:, 0] + plane[1] * vertices[:, 1] + plane[2] - vertices[:, 2]
    above = vertices[height > OBJECT_HEIGHT_M]
    if len(above) == 0:
        return None
    lo, hi = above[:, :2].min(axis=0), above[:, :2].max(axis=0)
    depth0 = float(plane[0] * lo[0] + plane[1] * lo[1] + plane[2])
    origin = np.array([lo[0], lo[1], depth0])
    if not proposals:
        proposals = propose_point_sets(vertices[height > -0.05], plane)
    sets, symmetric = [], []
    for k, proposal in enumerate(proposals):
        name = f"corners-{k + 1}"
        sets.append({"id": name, "points": [[round(float(c), 3) for c in p - origin] for p in proposal.points]})
        if proposal.symmetric:
            symmetric.append(name)
    if targets and not sets:
        raise ReconstructionError(f"'{object_id}': no characteristic-point set was found to reference the targets to")
    centroids = [proposal.points.mean(axis=0) - origin for proposal in proposals]
    entry_targets = []
    for target in targets:
        at = np.asarray(target.at) - origin
        nearest = int(np.argmin([np.linalg.norm(c - at) for c in centroids]))
        entry_targets.append({"id": target.name, "at": [round(float(c), 3) for c in at],
                              "reference": sets[nearest]["id"], "standoff": target.standoff})
    size = [round(float(v), 2) for v in (*(hi - lo), float(height.max()))]
    entry: dict[str, Any] = {
        "id": object_id,
        "description": "reconstructed by `auv reconstruct`" + (
            f"; symmetric sets (the prior heading must choose): {', '.join(symmetric)}" if symmetric else ""),
        "pose": {"north": round(float(origin[0]), 3), "east": round(float(origin[1]), 3),
                 "depth": round(depth0, 3), "heading": 0.0},
        "size": [max(v, 0.01) for v in size],
        "characteristic_points": sets,
    }
    if entry_targets:
        entry["targets"] = entry_targets
    if mesh_file is not None:
        entry["mesh"] = mesh_file
    return entry


def reconstruct_run(run_dir: Path, object_id: str, out_dir: Path | None = None,
                    voxel_m: float = 0.02, targets: tuple[NamedTarget, ...] = (), element: str | None = None,
                    poses: str = "anchored", max_sigma_m: float | None = 0.06) -> dict[str, Any]:
    """Reconstruct the object from the run's recording (`find_recording`) and write the outputs; returns the
    report. `targets` (world NED) go into the database entry in its object frame. `poses`: "anchored" fuses at the
    navigation poses held together by stereo odometry (`mission.reconstruct_poses`), "navigation" at the
    recording's own. `max_sigma_m`: mesh only where the fused distance is that sure (`ReconstructionSettings`;
    None meshes every observed cube)."""
    import cv2

    from mission.reconstruct_io import render_picture, write_mesh, write_points
    from mission.reconstruct_model import object_model
    from mission.reconstruct_poses import POSE_SOURCES, anchored_recording
    from mission.reconstruct_sets import detected_point_sets
    from perception_plugins.reconstruction import RangeSettings, ReconstructionSettings, fuse_views, points_from_range

    if poses not in POSE_SOURCES:
        raise ReconstructionError(f"poses '{poses}': expected one of {', '.join(POSE_SOURCES)}")
    recording = read_recording(find_recording(run_dir, object_id, element))
    graph = None
    if poses == "anchored":
        recording, graph = anchored_recording(recording)
    out = out_dir or run_dir / "models" / object_id / "reconstruction"
    out.mkdir(parents=True, exist_ok=True)
    np.savetxt(out / "camera_poses.txt", recording.poses[:, :3, :4].reshape(-1, 12), fmt="%.9e")
    maps: list[Any] = []

    def views() -> Any:
        for left, right, T in zip(recording.left, recording.right, recording.poses, strict=True):
            pair = [cv2.imread(str(p), cv2.IMREAD_GRAYSCALE) for p in (left, right)]
            if pair[0] is None or pair[1] is None:
                raise ReconstructionError(f"cannot read {left} or {right}")
            yield pair[0], pair[1], T

    t0 = time.perf_counter()
    # Match at about 600 pixels across (1200×900 pairs at half resolution; small images as they are).
    scale = max(1, int(round(2.0 * recording.K[0, 2] / MATCH_WIDTH_PX)))
    settings = ReconstructionSettings(voxel_m=voxel_m, range=RangeSettings(scale=scale), max_sigma_m=max_sigma_m)
    result = fuse_views(views(), recording.K, recording.baseline, settings, maps)
    if len(result.mesh.faces) == 0:
        raise ReconstructionError(f"{recording.folder}: the range maps yield no surface")
    clouds, greys = [], []
    for rmap, T in zip(maps, recording.poses, strict=True):
        pts, _ = points_from_range(rmap, stride=4)
        clouds.append(pts @ T[:3, :3].T + T[:3, 3])
        v, u = np.nonzero(np.isfinite(rmap.depth[::4, ::4]))
        greys.append(rmap.image[::4, ::4][v, u])
    points = np.vstack(clouds)
    plane = seabed_plane(result.mesh.vertices)
    mesh = result.mesh
    region = isolate_object(mesh.vertices, plane)
    point_grey = np.concatenate(greys)
    if region is not None:  # keep the object and the seabed around its foot, not the seabed to the edge of the views
        lo, hi, plane = region
        lo, hi = lo - SEABED_MARGIN_M, hi + SEABED_MARGIN_M
        inside = np.all((mesh.vertices[:, :2] >= lo) & (mesh.vertices[:, :2] <= hi), axis=1)
        mesh = mesh.subset(inside[mesh.faces].all(axis=1))
        keep = np.all((points[:, :2] >= lo) & (points[:, :2] <= hi), axis=1)
        points, point_grey = points[keep], point_grey[keep]
    height = plane[0] * mesh.vertices[:, 0] + plane[1] * mesh.vertices[:, 1] + plane[2] - mesh.vertices[:, 2]
    above = mesh.vertices[height > OBJECT_HEIGHT_M]
    write_mesh(mesh, out)
    proposals = []
    if region is not None:
        proposals = detected_point_sets(recording, plane, region[0], region[1])
    sets_from = "detector" if proposals else "mesh corners"
    if region is not None and not proposals and max_sigma_m is not None:
        # Corners of every observed cube within the outputs' box: the sure mesh loses the edges they sit on.
        from perception_plugins.reconstruction import clean_mesh, extract_mesh
        from perception_plugins.reconstruction.keypoints import propose_point_sets

        loose = clean_mesh(extract_mesh(result.volume), settings.clean).vertices
        keep = np.all((loose[:, :2] >= lo) & (loose[:, :2] <= hi), axis=1)
        keep &= plane[0] * loose[:, 0] + plane[1] * loose[:, 1] + plane[2] - loose[:, 2] > -0.05
        proposals = propose_point_sets(loose[keep], plane)
        sets_from = "corners of every observed cube"
    entry = database_entry(object_id, mesh.vertices, plane, targets, "mesh.ply", proposals) if len(above) else None
    model: dict[str, Any] | None = None
    if entry is not None:
        import yaml

        entry["model"], model = object_model(recording, entry, out)
        if entry["model"] is None:
            del entry["model"]
        (out / "object.yaml").write_text(yaml.safe_dump({"objects": [entry]}, sort_keys=False), encoding="utf-8")
    write_points(points, point_grey, out / "points.ply")
    render_picture(mesh, out / "mesh.png", title=f"{object_id}: {len(mesh.faces):,} triangles")
    report: dict[str, Any] = {
        "object": object_id, "recording": str(recording.folder), "pose_file": recording.pose_file, "poses": poses,
        "graph": graph,
        "point_sets_from": sets_from,
        "frames": result.frames, "voxel_m": voxel_m, "match_scale": scale, "max_sigma_m": max_sigma_m,
        "triangles": int(len(mesh.faces)), "triangles_before_cleaning": int(len(result.raw_mesh.faces)),
        "area_m2": round(float(mesh.face_areas().sum()), 3),
        "seabed_plane": {"a": float(plane[0]), "b": float(plane[1]), "c": float(plane[2]),
                         "meaning": "depth = a*north + b*east + c"},
        "object_extent": ({"min": above.min(axis=0).round(3).tolist(), "max": above.max(axis=0).round(3).tolist(),
                           "height_m": round(float(height.max()), 3)} if len(above) else None),
        "seconds": {"depth_per_frame": float(np.median(result.depth_s)),
                    "fusion_per_frame": float(np.median(result.fusion_s)),
                    "extract_and_clean": result.extract_s, "wall_total": time.perf_counter() - t0},
        "volume_mb": round(result.volume.nbytes / 1e6, 2),
        "files": ["mesh.ply", "mesh.glb", "points.ply", "mesh.png", "report.json", "camera_poses.txt"]
        + (["object.yaml"] if entry is not None else []) + ([entry["model"]] if entry and "model" in entry else []),
        "model": model, "out": str(out),
    }
    (out / "report.json").write_text(json.dumps(report, indent=2) + "\n", encoding="utf-8")
    return report


__all__ = ["NamedTarget", "Recording", "ReconstructionError", "database_entry", "find_recording", "isolate_object",
           "parse_target", "read_recording", "reconstruct_run", "seabed_plane"]
