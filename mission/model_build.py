"""`auv model build`: a multi-view object model from a run folder's stereo recording (seed 000 §3.1).

Reads `RUN_DIR/stereo/` (KITTI layout, `mission.sim.stereo_record`) and the object's database entry in
`RUN_DIR/mission.yaml`. Views are the frames given, or else chosen automatically: the frame whose navigation camera
position is horizontally nearest the object's database centre, then the next nearest at least `spacing` metres from
those chosen, up to `count`. Only the images, the navigation poses (`nav.txt`) and the database are used — never
the true poses. An existing model can be extended with the run's views instead (`extend`).

The model's object frame (on a base segment, Figure 2) is tied to the database object's frame — the frame the
mission's characteristic points and targets are given in — by identifying those points in the views with the
`stereo-referencing` plug-in: T_database_object is the least-squares transform of the identified points of the
views that agree, placed in the object frame by each view's T_object_view. The chart is metres off the object
(that is why vehicles reference), so the database pose only serves as the search prior; only when no set is
identified does the tie fall back on navigation and the chart, and the report says so.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from mission.errors import AuvError
from mission.frames import invert, pose_matrix, transform_points

if TYPE_CHECKING:
    from perception_plugins.multiview import ViewInput


class ModelBuildError(AuvError):
    """A model cannot be built from a run folder (no recording, unknown object, no view over it)."""


@dataclass(frozen=True)
class BuildReport:
    path: Path
    views: list[str]
    table: list[dict[str, object]]
    full: dict[str, int]
    database_tie: str = ""


TIE_PRIOR_RADIUS_M = 4.0   # how far the chart plus navigation may be off (as the reference agent's search)
TIE_FINE_RADIUS_M = 0.4    # once one view has identified a set
TIE_AGREEMENT_M = 0.04     # views whose identifications place the points this close agree


def tie_to_database(views: list[tuple[ViewInput, np.ndarray]], sets: list[tuple[str, np.ndarray]], object_id: str,
                    T_world_db_chart: np.ndarray, tolerance: float = 0.05) -> tuple[np.ndarray | None, str]:
    """T_database_object from the views (`(ViewInput, T_object_view)` pairs) in which the `stereo-referencing`
    plug-in identifies one of the database's characteristic-point sets (`(set id, points)` in the database
    frame), with the chart and navigation as its prior; (None, why) when no view identifies a set."""
    from mission.plugin_api import PointSetModel, ReferencingRequest, StereoImages
    from mission.plugins import load_plugin
    from perception_plugins.referencing import rigid_transform

    plugin = load_plugin("stereo-referencing")()
    plugin.configure({})
    request_sets = tuple(PointSetModel(object_id, sid, pts) for sid, pts in sets)
    found: list[tuple[np.ndarray, np.ndarray, str]] = []   # (database points, object-frame points, view)
    # First with the chart as the prior (metres off); once a view identifies a set, the other views are tried
    # again with that identification carried through the views' own T_object_view (centimetres off).
    T_object_db: np.ndarray | None = None
    pending = list(range(len(views)))
    for _ in range(2):
        for k in list(pending):
            view, T_object_view = views[k]
            if T_object_db is None:
                prior, radius = invert(view.T_world_cam_nav) @ T_world_db_chart, TIE_PRIOR_RADIUS_M
            else:
                prior, radius = invert(T_object_view) @ T_object_db, TIE_FINE_RADIUS_M
            frame = StereoImages(0.0, view.left, view.right, view.K, view.baseline)
            result = plugin.process(frame, ReferencingRequest(request_sets, prior, tolerance, radius))
            if result.recognised and result.model_points is not None and result.points_cam is not None:
                found.append((result.model_points, transform_points(T_object_view, result.points_cam), view.name))
                pending.remove(k)
                if T_object_db is None:
                    T_object_db = T_object_view @ result.T_cam_object
        if T_object_db is None:
            break
    plugin.close()
    if not found:
        return None, "no characteristic-point set identified in the views"
    probe = np.vstack([d for d, _, _ in found])
    placed = [transform_points(rigid_transform(d, o), probe) for d, o, _ in found]
    groups = [[j for j in range(len(found)) if np.max(np.linalg.norm(placed[i] - placed[j], axis=1))
               <= TIE_AGREEMENT_M] for i in range(len(found))]
    best = max(groups, key=len)
    db = np.vstack([found[j][0] for j in best])
    obj = np.vstack([found[j][1] for j in best])
    T_object_db = rigid_transform(db, obj)
    rms = float(np.sqrt(np.mean(np.sum((transform_points(T_object_db, db) - obj) ** 2, axis=1))))
    names = ", ".join(found[j][2] for j in best)
    return invert(T_object_db), (f"characteristic points: {len(db)} identified in view(s) {names}, "
                                 f"residual {1e3 * rms:.1f} mm")


def choose_frames(nav_positions: np.ndarray, centre: np.ndarray, count: int = 3, spacing: float = 1.0,
                  radius: float = 6.0) -> list[int]:
    """Frame indices by proximity to the object (horizontal distance), at least `spacing` m apart, within
    `radius` m of the centre.

    >>> choose_frames(np.array([[0.0, 0, 5], [0.2, 0, 5], [1.5, 0, 5], [9, 0, 5]]), np.array([0.1, 0, 0]), 3)
    [0, 2]
    """
    d = np.linalg.norm(nav_positions[:, :2] - centre[:2], axis=1)
    chosen: list[int] = []
    for i in np.argsort(d, kind="stable"):
        if d[i] > radius or len(chosen) == count:
            break
        if all(np.linalg.norm(nav_positions[i, :2] - nav_positions[j, :2]) >= spacing for j in chosen):
            chosen.append(int(i))
    return chosen


def unique_name(name: str, taken: set[str]) -> str:
    """`name`, or `name-2`, `name-3`… when a view of the model being extended has it already (views are files
    named after them); the name is added to `taken`.

    >>> unique_name("000001", {"000001", "000001-2"})
    '000001-3'
    """
    out, k = name, 1
    while out in taken:
        k += 1
        out = f"{name}-{k}"
    taken.add(out)
    return out


def build_from_run(run_dir: str | Path, object_id: str, views: list[int] | None = None,
                   edits_path: str | Path | None = None, out: str | Path | None = None,
                   extend: str | Path | None = None, count: int = 3) -> BuildReport:
    """Build (or extend) the model of `object_id` from a run folder; write it and report what it holds."""
    from mission.language import load_mission
    from mission.sim.stereo_record import StereoRecordError, read_stereo_recording
    from perception_plugins.multiview import MultiviewError, ViewInput, build_model, extend_model, read_edits
    from perception_plugins.multiview.model_io import read_model, write_model

    run = Path(run_dir)
    try:
        rec = read_stereo_recording(run / "stereo")
    except StereoRecordError as exc:
        raise ModelBuildError(f"{run}: no stereo recording (run `auv simulate MISSION --record-stereo`): "
                              f"{exc}") from exc
    mission = load_mission(run / "mission.yaml")
    known = [o.id for o in mission.objects]
    if object_id not in known:
        raise ModelBuildError(f"{run / 'mission.yaml'}: no object '{object_id}' in the database "
                              f"(known: {', '.join(known) or 'none'})")
    entry = mission.object(object_id)
    T_world_db = pose_matrix(entry.pose.north, entry.pose.east, entry.pose.depth, entry.pose.heading)
    centre = transform_points(T_world_db, np.array([[entry.size[0] / 2, entry.size[1] / 2, 0.0]]))[0]
    if views is None:
        views = choose_frames(rec.nav_poses[:, :3, 3], centre, count)
        if not views:
            raise ModelBuildError(f"{run}: no recorded frame within 6 m of {object_id}'s database position")
    bad = [i for i in views if not 0 <= i < len(rec)]
    if bad:
        raise ModelBuildError(f"{run}: frame(s) {bad} not in the recording (0…{len(rec) - 1})")
    try:
        base = read_model(extend) if extend is not None else None
    except MultiviewError as exc:
        raise ModelBuildError(str(exc)) from exc
    taken = {v.name for v in base.views} if base is not None else set()
    inputs = []
    for i in views:
        left, right = rec.images(i)
        inputs.append(ViewInput(unique_name(f"{i:06d}", taken), left, right, rec.K, rec.baseline, rec.nav_poses[i]))
    tie = "kept from the extended model"
    try:
        if base is not None:
            model = extend_model(base, inputs)
        else:
            edits = read_edits(edits_path) if edits_path is not None else None
            model = build_model(object_id, inputs, edits, T_world_database=T_world_db)
            sets = [(p.id, np.asarray(p.points, dtype=float)) for p in entry.characteristic_points]
            T_db_object, tie = tie_to_database(list(zip(inputs, [v.T_object_view for v in model.views],
                                                        strict=True)), sets, object_id, T_world_db) \
                if sets else (None, "the database object has no characteristic points")
            if T_db_object is not None:
                model.T_database_object = T_db_object
            else:
                tie = f"navigation and the chart ({tie})"
        path = write_model(model, out or extend or run / "models" / f"{object_id}.yaml")
    except MultiviewError as exc:
        raise ModelBuildError(str(exc)) from exc
    return BuildReport(path, [v.name for v in model.views], model.table(),
                       {"points": len(model.points), "lines": len(model.segments), "corners": len(model.corners)},
                       tie)


__all__ = ["BuildReport", "ModelBuildError", "build_from_run", "choose_frames", "tie_to_database", "unique_name"]
