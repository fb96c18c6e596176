"""The reference world's photo survey (issue 23): manifold-1 of worlds/sps_field.yaml photographed by an `explore`
element with `planner: rrt-photo`, after a small multibeam survey around it that makes its information map.

The mission is missions/sps_field_inspection.yaml (vehicle, sensors, safety, objects; no plug-ins) with the
route: to the field, a 60 × 60 m survey around manifold-1 at 20 m altitude (`actions: [map]`), the photo survey
(safe distance 4 m, 5 min), home. It prints the element's metrics and the planned information per metre of the
RIG plan against the spacing-scaled lawnmower over the same area and information map (same photo model), and
draws docs/figures/photo_survey_rig.png: the information map, the RIG path, the lawnmower's, the photo points
and the photographs taken.

    .venv/bin/python docs/missions/reference_photo_survey.py [RUN_DIR]
"""

import json
import math
import sys
import time
from pathlib import Path

import numpy as np
import yaml

from mission.agents.photo_survey import GAIN, OVERLAP
from mission.language.models import Mission
from mission.sim.run import simulate
from planners.rrt import InformationField, photo_survey_path
from planners.rrt.photo import footprint
from planners.rrt.photo_gain import PhotoModel, path_headings

ROOT = Path(__file__).resolve().parents[2]
ROUTE = [
    {"id": "to-field", "transit": {"to": {"north": 120, "east": 170}, "depth": 40, "navigation": "usbl"}},
    {"id": "manifold-survey", "survey": {"area": [[120, 170], [120, 230], [180, 230], [180, 170]], "sensor": "mbes",
                                         "altitude": 20, "overlap": "20%", "heading": "auto"}, "actions": ["map"]},
    {"id": "photos", "explore": {"object": "manifold-1", "sensor": "stereo", "planner": "rrt-photo",
                                 "safe_distance": 4, "budget": "5min"}},
    {"id": "home", "transit": {"to": "home", "depth": 0}},
]


def main() -> None:
    data = yaml.safe_load((ROOT / "missions" / "sps_field_inspection.yaml").read_text(encoding="utf-8"))
    data.pop("plugins")
    data["route"] = ROUTE
    data["world"] = str(ROOT / "worlds" / "sps_field.yaml")
    t0 = time.perf_counter()
    result = simulate(Mission.model_validate(data), out=sys.argv[1] if len(sys.argv) > 1 else None)
    m = result.metrics
    print(f"wall {time.perf_counter() - t0:.1f} s, completed {m['completed']}, "
          f"safety violations {len(m['safety_violations'])}")
    element = next(e for e in m["elements"] if e["kind"] == "explore")
    keys = ("status", "duration_s", "views", "path_length_m", "photo_coverage_percent", "photo_coverage_true_percent",
            "min_distance_to_object_m", "safe_distance_breached")
    print(json.dumps({k: element.get(k) for k in keys}, indent=1))
    print(json.dumps(element.get("objects"), indent=1))
    products = result.report.knowledge.maps["photos"]
    compare_and_draw(products, element)


def compare_and_draw(products: dict[str, np.ndarray], element: dict[str, object]) -> None:
    north0, east0, cell = (float(v) for v in products["photo_info_grid_0"])
    field = InformationField(products["photo_info_0"], north0, east0, cell)
    area = products["photo_areas"][0]
    path, points = products["photo_path"], products["photo_points"]
    fov = tuple(float(v) for v in element.get("camera_fov_deg", (62.0, 48.5)))  # type: ignore[attr-defined]
    altitude = float(next(iter(element["objects"]))["altitude_m"])  # type: ignore[call-overload, index]
    lawn = photo_survey_path(area, field, altitude=altitude, depth=float(path[0, 2]), fov_deg=fov, overlap=OVERLAP,
                             gain=GAIN, turning_radius=6.0)
    model = PhotoModel(field, *footprint(altitude, fov))

    def per_metre(p: np.ndarray, q: np.ndarray) -> tuple[float, float]:
        length = float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())
        counts = model.counts(q, path_headings(p, q))
        return model.revealed(counts) / length, length

    ours, theirs = per_metre(path, points), per_metre(lawn.path, lawn.photo_points)
    print(f"planned information per metre: RIG {ours[0]:.4f} over {ours[1]:.1f} m, lawnmower {theirs[0]:.4f} over "
          f"{theirs[1]:.1f} m, ratio {ours[0] / theirs[0]:.2f}")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.5, 6.5))
    rows, cols = field.values.shape
    extent = (east0 - cell / 2, east0 + (cols - 0.5) * cell, north0 - cell / 2, north0 + (rows - 0.5) * cell)
    im = ax.imshow(field.normalised(), origin="lower", extent=extent, cmap="viridis")
    fig.colorbar(im, ax=ax, label="information Î (normalised I = B∗G)")
    ring = np.vstack([area, area[:1]])
    ax.plot(ring[:, 1], ring[:, 0], color="white", lw=1.2, label="area photographed")
    ax.plot(lawn.path[:, 1], lawn.path[:, 0], "--", color="0.75", lw=1.0, label="spacing-scaled lawnmower")
    ax.plot(path[:, 1], path[:, 0], color="tab:orange", lw=1.6, label="RIG path (planned)")
    ax.scatter(points[:, 1], points[:, 0], s=12, marker="x", color="white", label="photo points")
    index = products.get("photo_index", np.zeros((0, 5)))
    if len(index):
        ax.scatter(index[:, 2], index[:, 1], s=14, color="red", label=f"photos taken ({len(index)})", zorder=5)
    pad = 14.0
    ax.set_xlim(area[:, 1].min() - pad, area[:, 1].max() + pad)
    ax.set_ylim(area[:, 0].min() - pad, area[:, 0].max() + pad)
    ax.set_xlabel("east (m)")
    ax.set_ylabel("north (m)")
    ax.set_aspect("equal")
    ax.set_title(f"manifold-1, rrt-photo: info/m {ours[0]:.3f} vs lawnmower {theirs[0]:.3f} "
                 f"({ours[0] / theirs[0]:.2f}x); coverage {element.get('photo_coverage_true_percent')} %",
                 fontsize=9)
    ax.legend(loc="lower left", fontsize=7, framealpha=0.6)
    out = ROOT / "docs" / "figures" / "photo_survey_rig.png"
    fig.savefig(out, dpi=110, bbox_inches="tight")
    print(f"figure: {out.relative_to(ROOT)}")
    assert math.isfinite(ours[0])


if __name__ == "__main__":
    main()
