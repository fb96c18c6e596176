"""The survey figure of a run folder: the sensed height map with the coverage lines, the information map, and
the detections over the true objects (seed 002 §2.1, Fig. 4), drawn from `maps/ELEMENT.npz` and metrics.json."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Polygon as PatchPolygon

from mission.world.scene import Scene


def _extent(products: dict[str, np.ndarray]) -> tuple[float, float, float, float]:
    depth = products["depth"]
    cell, n0, e0 = float(products["cell"]), float(products["north0"]), float(products["east0"])
    rows, cols = depth.shape
    return e0 - cell / 2, e0 + cell * (cols - 0.5), n0 - cell / 2, n0 + cell * (rows - 0.5)


def _rectangle(det: dict[str, Any], heading_deg: float = 0.0) -> np.ndarray:
    h = math.radians(heading_deg)
    half_l, half_w = det["length"] / 2, det["width"] / 2
    corners = [(half_l, half_w), (half_l, -half_w), (-half_l, -half_w), (-half_l, half_w)]
    return np.array([(det["east"] + a * math.sin(h) + b * math.cos(h), det["north"] + a * math.cos(h) - b * math.sin(h))
                     for a, b in corners])


def survey_figure(element: str, products: dict[str, np.ndarray], metrics: dict[str, Any],
                  scene: Scene | None) -> Figure:
    """Three panels, east right and north up: height map and lines, information map, detections over truth."""
    fig = Figure(figsize=(17, 6), layout="constrained")
    height_ax, info_ax, det_ax = fig.subplots(1, 3, sharex=True, sharey=True)
    extent = _extent(products)
    depth = products["depth"]
    im = height_ax.imshow(depth, origin="lower", extent=extent, cmap="viridis_r")
    fig.colorbar(im, ax=height_ax, shrink=0.8, label="sensed depth [m]")
    for line in products.get("lines", np.zeros((0, 2, 2))):
        height_ax.plot(line[:, 1], line[:, 0], color="white", lw=0.8)
    coverage = metrics.get("coverage_percent", 0.0)
    height_ax.set_title(f"{element}: sensed depth and survey passes (coverage {coverage:.1f}%)")
    info = products["info"]
    im = info_ax.imshow(info, origin="lower", extent=extent, cmap="magma")
    fig.colorbar(im, ax=info_ax, shrink=0.8, label="information I = B * G [m/m]")
    info_ax.set_title(f"information map (blur sigma {float(products.get('nav_sigma_m', 0)):.2f} m)")
    det_ax.imshow(np.isfinite(depth), origin="lower", extent=extent, cmap="Greys", vmin=0, vmax=3, alpha=0.6)
    if scene is not None:
        for obj in scene.objects:
            x, y = obj.footprint.exterior.xy
            det_ax.fill(x, y, color="saddlebrown", alpha=0.6)
            det_ax.annotate(f"{obj.id} (truth)", (obj.footprint.centroid.x, obj.footprint.centroid.y),
                            xytext=(6, -12), textcoords="offset points", fontsize=8, color="saddlebrown")
    for det in metrics.get("detections", []):
        det_ax.add_patch(PatchPolygon(_rectangle(det, det.get("heading_deg", 0.0)), closed=True, fill=False, ec="red",
                                      lw=1.5))
        label = det.get("matched_id") or "unknown"
        err = det.get("position_error_m")
        det_ax.annotate(f"{det['id']} [{label}]" + (f" err {err:.2f} m" if err is not None else " FALSE ALARM"),
                        (det["east"], det["north"]), xytext=(6, 6), textcoords="offset points", fontsize=8, color="red")
    missed = metrics.get("missed", [])
    det_ax.set_title("detections (red) over the true objects" + (f"; missed: {', '.join(missed)}" if missed else ""))
    for ax in (height_ax, info_ax, det_ax):
        ax.set_xlabel("east [m]")
        ax.set_aspect("equal")
        ax.set_xlim(extent[0], extent[1])
        ax.set_ylim(extent[2], extent[3])
    height_ax.set_ylabel("north [m]")
    return fig
