"""The explore figure of a run folder (seed 002 §2.2.2, Figs. 7–8): the voxel model the vehicle built, the views
it scanned from and the path between them, in plan and in elevation, and the explored volume over time — drawn
from `maps/ELEMENT.npz` (estimated frame, as the agent had it) and metrics.json."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from scipy import ndimage

from mission.world.scene import Scene


def _views(ax: Axes, views: np.ndarray, x: int, y: int, arrows: bool) -> None:
    if not len(views):
        return
    ax.scatter(views[:, x], views[:, y], s=28, c="red", marker="o", zorder=5, label=f"views ({len(views)})")
    if arrows:
        h = np.radians(views[:, 4])
        ax.quiver(views[:, 2], views[:, 1], np.sin(h), np.cos(h), color="red", scale=18, width=0.004, zorder=5)
    for k, v in enumerate(views):
        ax.annotate(str(k + 1), (v[x], v[y]), xytext=(3, 3), textcoords="offset points", fontsize=6, color="red")


def seabed_under(points: np.ndarray, resolution: float, window_m: float = 4.0) -> np.ndarray:
    """The seabed's depth under each point, for drawing: the deepest occupied voxel of any column within
    `window_m` (an object narrower than the window hides the seabed under it, not around it)."""
    keys = np.floor(points[:, :2] / resolution).astype(np.int64)
    lo = keys.min(axis=0)
    shape = tuple(int(v) for v in keys.max(axis=0) - lo + 1)
    deepest = np.full(shape, -np.inf)
    np.maximum.at(deepest, (keys[:, 0] - lo[0], keys[:, 1] - lo[1]), points[:, 2])
    size = max(1, int(round(window_m / resolution)))
    floor = ndimage.maximum_filter(deepest, size=size, mode="nearest")
    return np.asarray(floor[keys[:, 0] - lo[0], keys[:, 1] - lo[1]])


def explore_figure(element: str, products: dict[str, np.ndarray], metrics: dict[str, Any],
                   scene: Scene | None) -> Figure:
    """Plan view and north–depth elevation of the map, views and path; explored volume over time."""
    fig = Figure(figsize=(18, 6.2), layout="constrained")
    plan, side, curve = fig.subplots(1, 3)
    occupied = np.asarray(products.get("explore_occupied", np.zeros((0, 4))), dtype=float)
    views = np.asarray(products.get("explore_views", np.zeros((0, 6))), dtype=float)
    track = np.asarray(products.get("explore_track", np.zeros((0, 4))), dtype=float)
    volume = np.asarray(products.get("explore_volume", np.zeros((0, 4))), dtype=float)
    boxes = np.asarray(products.get("explore_boxes", np.zeros((0, 6))), dtype=float)
    t0 = float(track[0, 0]) if len(track) else float(volume[0, 0]) if len(volume) else 0.0
    if len(boxes):
        lo, hi = boxes[:, :3].min(axis=0), boxes[:, 3:].max(axis=0)
        inside = ((occupied[:, :3] >= lo) & (occupied[:, :3] <= hi)).all(axis=1) if len(occupied) else []
        occupied = occupied[inside] if len(occupied) else occupied
        near = ((track[:, 1:3] >= lo[:2] - 5.0) & (track[:, 1:3] <= hi[:2] + 5.0)).all(axis=1)
        track = track[near] if len(track) else track
    if len(occupied):
        resolution = float(products.get("explore_resolution", 0.25))
        above = occupied[:, 2] < seabed_under(occupied[:, :3], resolution) - 0.4  # the object; seabed faint
        ground = occupied[~above]
        plan.scatter(ground[:, 1], ground[:, 0], c="0.85", s=2, marker="s", linewidths=0)
        o = occupied[above][np.argsort(-occupied[above][:, 2])]  # deepest first: the object's top shows in plan
        sc = plan.scatter(o[:, 1], o[:, 0], c=o[:, 2], s=4, cmap="viridis_r", marker="s", linewidths=0)
        fig.colorbar(sc, ax=plan, shrink=0.8, label="object voxel depth [m] (estimated frame; seabed grey)")
        side.scatter(ground[:, 0], ground[:, 2], c="0.8", s=2, marker="s", linewidths=0)
        side.scatter(o[:, 0], o[:, 2], c=o[:, 1], s=4, cmap="cividis", marker="s", linewidths=0)
    if scene is not None and len(boxes):
        for obj in scene.objects:
            c = obj.footprint.centroid
            if lo[0] - 5 <= c.y <= hi[0] + 5 and lo[1] - 5 <= c.x <= hi[1] + 5:
                x, y = obj.footprint.exterior.xy
                plan.plot(x, y, color="saddlebrown", lw=1.2, label=f"{obj.id} (true footprint)")
    if len(track):
        plan.plot(track[:, 2], track[:, 1], color="tab:orange", lw=0.9, label="path (estimated)")
        side.plot(track[:, 1], track[:, 3], color="tab:orange", lw=0.9, label="path (estimated)")
    _views(plan, views, 2, 1, arrows=True)
    _views(side, views, 1, 3, arrows=False)
    observed = metrics.get("surface_observed_percent")
    d_min = metrics.get("min_distance_to_object_m")
    title = f"{element}: voxel model, views and path"
    if observed is not None:
        title += f"\n{observed:.1f}% of the true surface observed"
    if d_min is not None:
        title += f"\nclosest approach {d_min:.2f} m (safe distance {metrics.get('safe_distance_m', math.nan):g} m)"
    plan.set_title(title, fontsize=10)
    plan.set_xlabel("east [m]")
    plan.set_ylabel("north [m]")
    plan.set_aspect("equal")
    plan.legend(loc="upper right", fontsize=7)
    side.set_title("elevation: north against depth (voxels coloured by east)", fontsize=10)
    side.set_xlabel("north [m]")
    side.set_ylabel("depth [m]")
    side.invert_yaxis()
    side.set_aspect("equal")
    if len(volume):
        curve.plot(volume[:, 0] - t0, volume[:, 1] - volume[0, 1], color="tab:blue", label="explored volume")
        curve.set_ylabel("volume explored since the first frame [m³] (beyond the survey's prior)",
                         color="tab:blue")
        twin = curve.twinx()
        twin.plot(volume[:, 0] - t0, 100.0 * volume[:, 2], color="tab:green", label="surface estimate (agent)")
        twin.set_ylabel("agent's surface estimate [%]", color="tab:green")
        twin.set_ylim(0, 100)
        if len(views):
            for v in views:
                curve.axvline(v[0] - t0, color="red", lw=0.4, alpha=0.5)
    curve.set_xlabel("time since the element began [s] (red: views)")
    curve.set_title("explored volume over time", fontsize=10)
    return fig


def photo_figure(element: str, products: dict[str, np.ndarray], metrics: dict[str, Any],
                 scene: Scene | None) -> Figure:
    """A photo survey (seed 002 §2.2.1) in plan: the planned passes and turns, the photo points, the footprints of
    the photographs taken (at their estimated poses) over the object's area and its true footprint."""
    from mission.agents.photo_survey import footprint_polygon

    fig = Figure(figsize=(8, 7.5), layout="constrained")
    ax = fig.subplots()
    path = np.asarray(products.get("photo_path", np.zeros((0, 3))), dtype=float)
    points = np.asarray(products.get("photo_points", np.zeros((0, 3))), dtype=float)
    index = np.asarray(products.get("photo_index", np.zeros((0, 5))), dtype=float)
    areas = np.asarray(products.get("photo_areas", np.zeros((0, 4, 2))), dtype=float)
    fov = metrics.get("camera_fov_deg")
    objects = metrics.get("objects", [])
    if fov and len(index) and objects:
        altitude = float(objects[0].get("altitude_m", 5.0))
        for k, (_, n, e, _, h) in enumerate(index):
            poly = footprint_polygon(n, e, h, 2 * altitude * math.tan(math.radians(fov[0] / 2)),
                                     2 * altitude * math.tan(math.radians(fov[1] / 2)))
            x, y = poly.exterior.xy
            ax.fill(x, y, color="tab:blue", alpha=0.08, label="photo footprints (estimated poses)" if k == 0
                    else None)
            ax.plot(x, y, color="tab:blue", lw=0.4)
    for k, area in enumerate(areas):
        ring = np.vstack([area, area[:1]])
        ax.plot(ring[:, 1], ring[:, 0], color="teal", lw=1.5, label="area photographed" if k == 0 else None)
    if scene is not None and len(areas):
        c = areas.reshape(-1, 2).mean(axis=0)
        for obj in scene.objects:
            if math.hypot(obj.footprint.centroid.y - c[0], obj.footprint.centroid.x - c[1]) < 30.0:
                x, y = obj.footprint.exterior.xy
                ax.fill(x, y, color="saddlebrown", alpha=0.5, label=f"{obj.id} (true)")
    if len(path):
        ax.plot(path[:, 1], path[:, 0], color="tab:purple", lw=1.0, label="planned passes and turns")
    if len(points):
        ax.scatter(points[:, 1], points[:, 0], s=14, marker="x", color="tab:purple", label="photo points")
    if len(index):
        ax.scatter(index[:, 2], index[:, 1], s=16, color="red", label=f"photos taken ({len(index)})", zorder=5)
    cover = metrics.get("photo_coverage_percent")
    true_cover = metrics.get("photo_coverage_true_percent")
    title = f"{element}: photo survey"
    if cover is not None:
        title += f"; coverage {cover:.1f}% (estimated)"
    if true_cover is not None:
        title += f", {true_cover:.1f}% (true poses)"
    ax.set_title(title, fontsize=10)
    ax.set_xlabel("east [m]")
    ax.set_ylabel("north [m]")
    ax.set_aspect("equal")
    ax.legend(loc="best", fontsize=7)
    return fig
