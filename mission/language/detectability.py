"""How detectable each characteristic-point set is (seed 002 §3.3's preliminary pass), rated from the set's
geometry and the stereo camera, fast enough for `auv validate`.

What the rating stands for was measured on the reference world's rendered fine views
(`benchmarks/set_diagnosis.py`, `benchmarks/results/set_diagnosis.json`): a set is recognised when the whole of
it is in the view, so it is viewed from the range at which it fits in `VIEW_FILL` of the image (its longer side
along the image's width), never closer than the seed's 3.6 m; the stereo depth error there grows as
σ_Z = Z²·σ_d/(f·B), and the identification's tolerance with it, so a set that must be viewed from twice the range
is identified with four times the slack, among four times as many chance coincidences. A set of three points has
no redundancy (any three points fit some triangle of a dense cloud), and points closer together in the image than
`MIN_SPACING_PX` merge into one corner. The rating multiplies these factors:

    rating = (3.6 m / view range)² · min(1, (points − 2) / 3) · min(1, spacing in pixels / MIN_SPACING_PX)

0 when the set cannot be seen whole inside the stereo range or has fewer than three points. The inspect agent
prefers sets with a higher rating when it chooses the set to reference through.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mission.language.models import KnownObject, Mission, Stereo

FINE_RANGE_M = 3.6  # the seed's fine-view range: nothing is gained closer, the whole set must be in view
VIEW_FILL = 0.75  # a set spans at most this share of the image in its view (as the inspect agent frames it)
SIGMA_D_PX = 0.25  # disparity uncertainty after sub-pixel refinement (perception_plugins.stereo.pipeline)
MIN_SPACING_PX = 40.0  # characteristic points closer than this in the image compete for one corner
RANGE_MARGIN_M = 0.5  # the set's deepest point stays this far inside the stereo range


@dataclass(frozen=True)
class Detectability:
    """A set's rating (0–1, higher is more detectable) and the figures behind it."""

    set_id: str
    rating: float
    view_range_m: float
    sigma_z_m: float
    spacing_px: float
    points: int
    reason: str

    def describe(self) -> str:
        return (f"point set '{self.set_id}' detectability {self.rating:.2f}: {self.reason}")


def rate_set(set_id: str, points: np.ndarray, camera: Stereo) -> Detectability:
    """Rate one set (object frame, z down) for a down-looking stereo camera.

    >>> s = Stereo(width=1200, height=900, fx=1000.0, baseline=0.25, max_range=8.0)
    >>> tall = rate_set("top", np.array([[2, 1, -2], [6, 1, -2], [6, 4, -2], [2, 4, -2], [4, 2.5, -2.6]]), s)
    >>> low = rate_set("skid", np.array([[8, 0, 0], [8, 5, 0], [7, .5, -.3], [7, 4.5, -.3], [6.5, 2.5, -.4]]), s)
    >>> bool(tall.rating > low.rating > 0)
    True
    """
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    n = len(pts)
    if n < 3:
        return Detectability(set_id, 0.0, math.nan, math.nan, math.nan, n,
                             f"{n} point(s): at least 3 are needed to reference")
    extent = np.sort(np.ptp(pts[:, :2], axis=0))[::-1]
    fit = max(extent[0] / (VIEW_FILL * camera.width / camera.fx), extent[1] / (VIEW_FILL * camera.height / camera.fx))
    relief = float(np.ptp(pts[:, 2]))
    view = max(FINE_RANGE_M, fit) + relief
    sigma_z = view ** 2 * SIGMA_D_PX / (camera.fx * camera.baseline)
    gaps = np.linalg.norm(pts[:, None, :2] - pts[None, :, :2], axis=2) + np.eye(n) * 1e9
    spacing = float(gaps.min()) * camera.fx / view
    if view > camera.max_range - RANGE_MARGIN_M:
        return Detectability(set_id, 0.0, view, sigma_z, spacing, n,
                             f"seen whole only from {view:.1f} m, beyond the stereo range "
                             f"({camera.max_range:g} m less a {RANGE_MARGIN_M:g} m margin)")
    rating = (FINE_RANGE_M / view) ** 2 * min(1.0, (n - 2) / 3.0) * min(1.0, spacing / MIN_SPACING_PX)
    reason = (f"{n} points, seen whole from {view:.1f} m (σ_Z {100 * sigma_z:.1f} cm there), "
              f"closest two {spacing:.0f} px apart")
    return Detectability(set_id, round(rating, 3), view, sigma_z, spacing, n, reason)


def rate_object(obj: KnownObject, camera: Stereo | None) -> list[Detectability]:
    """Every set of an object, in the database's order."""
    cam = camera or Stereo()
    return [rate_set(s.id, np.asarray(s.points, dtype=float), cam) for s in obj.characteristic_points]


def detectability_notes(path: str | Path, mission: Mission) -> list[str]:
    """`FILE:LINE:COL: note: …` for every characteristic-point set of a valid mission, at the set's line."""
    from mission.language.source import read_yaml

    doc = read_yaml(Path(path))
    camera = mission.sensors.stereo
    notes = []
    for i, obj in enumerate(mission.objects):
        for k, rated in enumerate(rate_object(obj, camera)):
            line, col = doc.where(("objects", i, "characteristic_points", k))
            notes.append(f"{path}:{line}:{col}: note: {rated.describe()}")
    return notes


__all__ = ["Detectability", "detectability_notes", "rate_object", "rate_set"]
