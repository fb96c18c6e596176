"""The multi-view object model `auv reconstruct` builds beside the mesh, so that a later mission can reference
itself to the object (seed 000 §3.1: a model from overview views; `perception_plugins.multiview`).

The views are the recording's frames nearest the object's centre (horizontally, within `MODEL_RADIUS_M`, at least
`MODEL_SPACING_M` apart: `mission.model_build.choose_frames`) at the poses the mesh was fused at. The model's tie to
the database entry (`T_database_object`) needs no identification here: the entry's frame was made from the same
recording at the same poses, so navigation and the entry tie them exactly as far as those poses agree with each
other (`auv model build` identifies characteristic points instead, because there the database was charted
apart from the views). The entry names the model with `model:`; a mission that knows the object from the entry and
uses the `multiview-referencing` plug-in recognises the object in its stereo pairs by the model's points and
lines, where the few corners of a low, grey structure on textured sand would not stand out among the
`stereo-referencing` plug-in's corners (README, "The loop").
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from mission.frames import pose_matrix, transform_points
from mission.reconstruct import ReconstructionError, Recording

MODEL_VIEWS = 3
MODEL_RADIUS_M = 6.0
MODEL_SPACING_M = 1.0


def object_model(recording: Recording, entry: dict[str, Any], out: Path) -> tuple[str | None, dict[str, Any]]:
    """Build and write the model of the entry's object (module docstring) to `out/model/ID.yaml`; returns the path
    relative to `out` (None when no frame is near enough) and a report (views, what the model holds, or why
    not)."""
    import cv2

    from mission.model_build import choose_frames
    from perception_plugins.multiview import MultiviewError, ViewInput, build_model
    from perception_plugins.multiview.model_io import write_model

    pose = entry["pose"]
    T_world_db = pose_matrix(pose["north"], pose["east"], pose["depth"], pose["heading"])
    centre = transform_points(T_world_db, np.array([[entry["size"][0] / 2, entry["size"][1] / 2, 0.0]]))[0]
    frames = choose_frames(recording.poses[:, :3, 3], centre, MODEL_VIEWS, MODEL_SPACING_M, MODEL_RADIUS_M)
    if not frames:
        return None, {"views": [], "why_not": f"no recorded frame within {MODEL_RADIUS_M:g} m of the object"}
    inputs = []
    for k in frames:
        left = cv2.imread(str(recording.left[k]), cv2.IMREAD_GRAYSCALE)
        right = cv2.imread(str(recording.right[k]), cv2.IMREAD_GRAYSCALE)
        if left is None or right is None:
            raise ReconstructionError(f"cannot read {recording.left[k]} or {recording.right[k]}")
        inputs.append(ViewInput(f"{k:06d}", np.asarray(left, np.uint8), np.asarray(right, np.uint8), recording.K,
                                recording.baseline, recording.poses[k]))
    relative = f"model/{entry['id']}.yaml"
    try:
        model = build_model(entry["id"], inputs, T_world_database=T_world_db)
        write_model(model, out / relative)
    except MultiviewError as exc:
        return None, {"views": [v.name for v in inputs], "why_not": str(exc)}
    return relative, {"views": [v.name for v in inputs], "points": len(model.points), "lines": len(model.segments),
                      "corners": len(model.corners)}


__all__ = ["MODEL_RADIUS_M", "MODEL_SPACING_M", "MODEL_VIEWS", "object_model"]
