"""An operator's edits to an automatically built model (seed 000 §3.1: the operator selects points, adds points,
indicates edges and the base segment), read from YAML. Everything is picked in a view's left-image pixels:

```yaml
base: {view: "000120", edge: [[412, 300], [780, 310]]}   # the base segment: the view's edge nearest these ends
views:
  "000120":
    add_edges: [[[100, 200], [300, 205]]]                 # edges the detector missed (end points in the image)
    remove_edges: [[640, 480]]                            # the edge passing nearest this pixel
    add_points: [[512, 384]]                              # matched along the epipolar row and triangulated
    remove_points: [{at: [600, 450], radius: 40}]         # every point within the radius (px)
```
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from numpy.typing import NDArray

from perception_plugins.multiview.errors import MultiviewError

Array = NDArray[np.float64]


@dataclass(frozen=True)
class ViewEdits:
    add_edges: list[Array] = field(default_factory=list)          # each (2, 2) pixels
    remove_edges: list[Array] = field(default_factory=list)       # each (2,) pixel
    add_points: list[Array] = field(default_factory=list)         # each (2,) pixel
    remove_points: list[tuple[Array, float]] = field(default_factory=list)


@dataclass(frozen=True)
class Edits:
    base_view: str | None = None
    base_edge: Array | None = None                                # (2, 2) pixels
    views: dict[str, ViewEdits] = field(default_factory=dict)

    def for_view(self, name: str) -> ViewEdits:
        return self.views.get(name, ViewEdits())


def _pixels(value: Any, shape: tuple[int, ...], where: str) -> Array:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise MultiviewError(f"{where}: expected numbers of shape {shape}, got {value!r}") from exc
    if arr.shape != shape or not np.all(np.isfinite(arr)):
        raise MultiviewError(f"{where}: expected pixel coordinates of shape {shape}, got {value!r}")
    return arr


def parse_edits(data: Any, source: str = "edits") -> Edits:
    """Edits from a parsed YAML mapping; every malformed entry raises `MultiviewError` naming it."""
    if data is None:
        return Edits()
    if not isinstance(data, dict):
        raise MultiviewError(f"{source}: expected a mapping with 'base' and/or 'views'")
    unknown = set(data) - {"base", "views"}
    if unknown:
        raise MultiviewError(f"{source}: unknown key(s) {', '.join(sorted(unknown))} (expected base, views)")
    base_view, base_edge = None, None
    if data.get("base") is not None:
        base = data["base"]
        if not isinstance(base, dict) or set(base) != {"view", "edge"}:
            raise MultiviewError(f"{source}: base must be {{view: NAME, edge: [[u1, v1], [u2, v2]]}}")
        base_view, base_edge = str(base["view"]), _pixels(base["edge"], (2, 2), f"{source}: base.edge")
    views: dict[str, ViewEdits] = {}
    for name, entry in (data.get("views") or {}).items():
        where = f"{source}: views.{name}"
        if not isinstance(entry, dict):
            raise MultiviewError(f"{where}: expected a mapping")
        unknown = set(entry) - {"add_edges", "remove_edges", "add_points", "remove_points"}
        if unknown:
            raise MultiviewError(f"{where}: unknown key(s) {', '.join(sorted(unknown))}")
        removes = []
        for i, r in enumerate(entry.get("remove_points") or []):
            if not isinstance(r, dict) or "at" not in r:
                raise MultiviewError(f"{where}.remove_points[{i}]: expected {{at: [u, v], radius: px}}")
            removes.append((_pixels(r["at"], (2,), f"{where}.remove_points[{i}].at"), float(r.get("radius", 10))))
        views[str(name)] = ViewEdits(
            [_pixels(e, (2, 2), f"{where}.add_edges[{i}]") for i, e in enumerate(entry.get("add_edges") or [])],
            [_pixels(e, (2,), f"{where}.remove_edges[{i}]") for i, e in enumerate(entry.get("remove_edges") or [])],
            [_pixels(e, (2,), f"{where}.add_points[{i}]") for i, e in enumerate(entry.get("add_points") or [])],
            removes)
    return Edits(base_view, base_edge, views)


def read_edits(path: str | Path) -> Edits:
    """Edits from a YAML file."""
    p = Path(path)
    try:
        data = yaml.safe_load(p.read_text(encoding="utf-8"))
    except (OSError, yaml.YAMLError) as exc:
        raise MultiviewError(f"{p}: cannot read the edits: {exc}") from exc
    return parse_edits(data, str(p))


__all__ = ["Edits", "ViewEdits", "parse_edits", "read_edits"]
