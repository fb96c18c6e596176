"""The explore figure of a run folder (seed 002 §2.2.2, Figs. 7–8): the voxel model the vehicle built, the views
it scanned from and the path between them, in plan and in elevation, and the explored volume over time — drawn
from `maps/ELEMENT.npz` (estimated frame, as the agent had it) and metrics.json."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

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
    if len(boxes):
        lo, hi = boxes[:, :3].min(axis=0), boxes[:, 3:].max(axis=0)
        inside = ((occupied[:, :3] >= lo) & (occupied[:, :3] <= hi)).all(axis=1) if len(occupied) else []
        occupied = occupied[inside] if len(occupied) else occupied
        near = ((track[:, 1:3] >= lo[:2] - 5.0) & (track[:, 1:3] <= hi[:2] + 5.0)).all(axis=1)
        track = track[near] if len(track) else track
    if len(occupied):
        order = np.argsort(-occupied[:, 2])  # draw the deepest first, so the object's top shows in plan
        o = occupied[order]
        sc = plan.scatter(o[:, 1], o[:, 0], c=o[:, 2], s=3, cmap="viridis_r", marker="s", linewidths=0)
        fig.colorbar(sc, ax=plan, shrink=0.8, label="occupied voxel depth [m] (estimated frame)")
        side.scatter(o[:, 0], o[:, 2], c=o[:, 1], s=3, cmap="cividis", marker="s", linewidths=0)
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
        title += f"\nsurface observed {observed:.1f}% of the true surface voxels"
    if d_min is not None:
        title += f"; closest approach {d_min:.2f} m (safe {metrics.get('safe_distance_m', math.nan):g} m)"
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
        t0 = float(track[0, 0]) if len(track) else float(volume[0, 0])
        curve.plot(volume[:, 0] - t0, volume[:, 1], color="tab:blue", label="explored (known) volume")
        curve.set_ylabel("known volume in the exploration box [m³]", color="tab:blue")
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
