"""`auv model build`: a multi-view object model from a run folder's stereo recording (seed 000 §3.1).

Reads `RUN_DIR/stereo/` (KITTI layout, `mission.sim.stereo_record`) and the object's database entry in
`RUN_DIR/mission.yaml`. Views are the frames given, or else chosen automatically: the frame whose navigation camera
position is horizontally nearest the object's database centre, then the next nearest at least `spacing` metres from
those chosen, up to `count`. Only the images, the navigation poses (`nav.txt`) and the database are used — never
the true poses. An existing model can be extended with the run's views instead (`extend`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mission.errors import AuvError
from mission.frames import pose_matrix, transform_points


class ModelBuildError(AuvError):
    """A model cannot be built from a run folder (no recording, unknown object, no view over it)."""


@dataclass(frozen=True)
class BuildReport:
    path: Path
    views: list[str]
    table: list[dict[str, object]]
    full: dict[str, int]


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
    inputs = []
    for i in views:
        left, right = rec.images(i)
        inputs.append(ViewInput(f"{i:06d}", left, right, rec.K, rec.baseline, rec.nav_poses[i]))
    try:
        if extend is not None:
            model = extend_model(read_model(extend), inputs)
        else:
            edits = read_edits(edits_path) if edits_path is not None else None
            model = build_model(object_id, inputs, edits, T_world_database=T_world_db)
        path = write_model(model, out or extend or run / "models" / f"{object_id}.yaml")
    except MultiviewError as exc:
        raise ModelBuildError(str(exc)) from exc
    return BuildReport(path, [v.name for v in model.views], model.table(),
                       {"points": len(model.points), "lines": len(model.segments), "corners": len(model.corners)})


__all__ = ["BuildReport", "ModelBuildError", "build_from_run", "choose_frames"]
