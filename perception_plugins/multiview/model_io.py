"""Reading and writing multi-view models: `NAME.yaml` (object, frames, views, counts: what a person reads and a
mission references) and the folder `NAME.views/` beside it (each view's left image as PNG and its elements as
NPZ; the full model's averaged elements in `full.npz`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import cv2
import numpy as np
import yaml

from perception_plugins.multiview.corners import Corner
from perception_plugins.multiview.errors import MultiviewError
from perception_plugins.multiview.model import ObjectModel, ViewModel
from perception_plugins.multiview.segments import Segment

FORMAT = "auv-multiview-model/1"


def _views_dir(path: Path) -> Path:
    return path.with_name(path.stem + ".views")


def _matrix(value: Any, shape: tuple[int, ...], where: str) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.shape != shape:
        raise MultiviewError(f"{where}: expected a matrix of shape {shape}")
    return arr


def write_model(model: ObjectModel, path: str | Path) -> Path:
    """Write the model; returns the YAML file's path."""
    p = Path(path)
    names = [v.name for v in model.views]
    if len(set(names)) != len(names):   # each view is a pair of files named after it
        raise MultiviewError(f"{p}: the model's view names are not unique ({', '.join(names)})")
    folder = _views_dir(p)
    folder.mkdir(parents=True, exist_ok=True)
    views = []
    for v in model.views:
        cv2.imwrite(str(folder / f"{v.name}_left.png"), v.left)
        segs = v.segments
        np.savez_compressed(
            folder / f"{v.name}.npz", points=v.points, uv_left=v.uv_left, descriptors=v.descriptors,
            seg_uv_left=np.array([s.uv_left for s in segs]).reshape(-1, 2, 2),
            seg_uv_right=np.array([s.uv_right for s in segs]).reshape(-1, 2, 2),
            seg_points=np.array([s.points for s in segs]).reshape(-1, 2, 3),
            seg_side=np.array([s.side for s in segs]), seg_score=np.array([s.score for s in segs]).reshape(-1, 2),
            corners=np.array([[*c.segments, *c.ends] for c in v.corners], dtype=np.int64).reshape(-1, 4),
            point_ids=v.point_ids, segment_ids=v.segment_ids, corner_ids=v.corner_ids)
        views.append({"name": v.name, "K": v.K.tolist(), "baseline": v.baseline,
                      "T_world_view_nav": np.round(v.T_world_view_nav, 9).tolist(),
                      "T_object_view": np.round(v.T_object_view, 9).tolist(),
                      "counts": {"points": len(v.points), "lines": len(v.segments), "corners": len(v.corners)}})
    np.savez_compressed(folder / "full.npz", points=model.points, segments=model.segments, corners=model.corners)
    doc = {"format": FORMAT, "object": model.object_id, "detector": model.detector,
           "base_segment": np.round(model.base_segment, 6).tolist(),
           "T_database_object": np.round(model.T_database_object, 9).tolist(),
           "full_model": {"points": len(model.points), "lines": len(model.segments), "corners": len(model.corners)},
           "views": views}
    p.write_text(yaml.safe_dump(doc, sort_keys=False, width=120), encoding="utf-8")
    return p


def read_model(path: str | Path) -> ObjectModel:
    """Read a model written by `write_model`; a missing or malformed part raises `MultiviewError`."""
    p = Path(path)
    try:
        doc = yaml.safe_load(p.read_text(encoding="utf-8"))
    except (OSError, yaml.YAMLError) as exc:
        raise MultiviewError(f"{p}: cannot read the model: {exc}") from exc
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        raise MultiviewError(f"{p}: not a multi-view model (expected format: {FORMAT})")
    folder = _views_dir(p)
    views = []
    try:
        for entry in doc["views"]:
            name = str(entry["name"])
            left = cv2.imread(str(folder / f"{name}_left.png"), cv2.IMREAD_GRAYSCALE)
            if left is None:
                raise MultiviewError(f"{p}: view {name}: missing image {folder / f'{name}_left.png'}")
            with np.load(folder / f"{name}.npz") as z:
                segs = [Segment(z["seg_uv_left"][i], z["seg_uv_right"][i], z["seg_points"][i],
                                float(z["seg_side"][i]), z["seg_score"][i]) for i in range(len(z["seg_side"]))]
                corners = [Corner((int(c[0]), int(c[1])), (int(c[2]), int(c[3]))) for c in z["corners"]]
                views.append(ViewModel(name, _matrix(entry["K"], (3, 3), f"{p}: {name}.K"), float(entry["baseline"]),
                                       np.asarray(left, np.uint8),
                                       _matrix(entry["T_world_view_nav"], (4, 4), f"{p}: {name}.T_world_view_nav"),
                                       _matrix(entry["T_object_view"], (4, 4), f"{p}: {name}.T_object_view"),
                                       z["points"], z["uv_left"], z["descriptors"], segs, corners,
                                       z["point_ids"], z["segment_ids"], z["corner_ids"]))
        with np.load(folder / "full.npz") as z:
            full = {k: z[k] for k in ("points", "segments", "corners")}
        return ObjectModel(str(doc["object"]), views, str(doc.get("detector", "sift")),
                           _matrix(doc["base_segment"], (2, 3), f"{p}: base_segment"), full["points"],
                           full["segments"], full["corners"],
                           _matrix(doc["T_database_object"], (4, 4), f"{p}: T_database_object"))
    except (KeyError, TypeError, ValueError, OSError) as exc:
        raise MultiviewError(f"{p}: malformed model ({type(exc).__name__}: {exc})") from exc


__all__ = ["FORMAT", "read_model", "write_model"]
