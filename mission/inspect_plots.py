"""The inspection figure of a run folder (seed 002 §3.4, Figs 11–13): in the object's own frame, the point sets
and targets, the visiting order as planned (and re-planned), the path the vehicle truly flew and where the camera
truly was at each photograph. Drawn from metrics.json, trajectory.csv and the world."""

from __future__ import annotations

from typing import Any

import numpy as np
from matplotlib.figure import Figure

from mission.frames import camera_pose, invert, transform_points
from mission.language.models import Mission
from mission.world.scene import Scene

SET_COLORS = ("tab:blue", "tab:green", "tab:red", "tab:purple", "tab:brown", "tab:cyan")


def _stop_position(mission: Mission, object_id: str, stop: list[str]) -> np.ndarray | None:
    obj = mission.object(object_id)
    kind, ident = stop
    if kind == "set":
        pts = next((s.points for s in obj.characteristic_points if s.id == ident), None)
        return None if pts is None else np.asarray(pts, dtype=float).mean(axis=0)
    if kind == "target":
        at = next((t.at for t in obj.targets if t.id == ident), None)
        return None if at is None else np.asarray(at, dtype=float)
    return None


def inspect_figure(element: str, item: dict[str, Any], mission: Mission, trajectory: dict[str, np.ndarray],
                   elements: list[str], scene: Scene | None) -> Figure:
    """Plan view (x along the object, y across) and side view (x, height), both in the object frame."""
    obj = mission.object(item["object"])
    fig = Figure(figsize=(15, 6.5), layout="constrained")
    plan, side = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.3, 1]})
    L, W, _ = obj.size
    outline = np.array([[0, 0], [L, 0], [L, W], [0, W], [0, 0]])
    plan.plot(outline[:, 0], outline[:, 1], color="0.5", lw=1, label="charted footprint")
    for k, pset in enumerate(obj.characteristic_points):
        p = np.asarray(pset.points, dtype=float)
        color = SET_COLORS[k % len(SET_COLORS)]
        plan.scatter(p[:, 0], p[:, 1], marker="s", s=30, color=color, label=f"set {pset.id}")
        side.scatter(p[:, 0], -p[:, 2], marker="s", s=30, color=color)
    for t in obj.targets:
        plan.scatter([t.at[0]], [t.at[1]], marker="*", s=140, color="gold", edgecolor="k", zorder=5)
        plan.annotate(t.id, (t.at[0], t.at[1]), xytext=(4, 4), textcoords="offset points", fontsize=8)
        side.scatter([t.at[0]], [-t.at[2]], marker="*", s=140, color="gold", edgecolor="k", zorder=5)
    # the order: stops as listed (a re-plan starts a new dashed chain)
    chains: list[list[np.ndarray]] = [[]]
    for stop in item.get("order", []):
        if stop[0] == "replan":
            chains.append([])
            continue
        position = _stop_position(mission, obj.id, stop)
        if position is not None:
            chains[-1].append(position)
    for i, chain in enumerate(chains):
        if len(chain) >= 2:
            c = np.array(chain)
            plan.plot(c[:, 0], c[:, 1], ls="--" if i else "-", color="tab:purple", lw=1.5, alpha=0.8,
                      label="order" if i == 0 else ("re-planned order" if i == 1 else None))
            for a, b in zip(c[:-1], c[1:], strict=True):
                plan.annotate("", xy=b[:2], xytext=a[:2],
                              arrowprops={"arrowstyle": "->", "color": "tab:purple", "lw": 1.2})
    truth = next((o for o in scene.objects if o.database == obj.id), None) if scene is not None else None
    if truth is not None and len(trajectory.get("time", [])):
        mask = np.array([e == element for e in elements])
        world = np.column_stack([trajectory["north"], trajectory["east"], trajectory["depth"]])[mask]
        local = transform_points(invert(truth.T_world_object), world)
        plan.plot(local[:, 0], local[:, 1], color="k", lw=0.8, label="flown (truth)")
        side.plot(local[:, 0], -local[:, 2], color="k", lw=0.8)
        baseline = mission.sensors.stereo.baseline if mission.sensors.stereo is not None else 0.0
        times = trajectory["time"]
        cams = []
        for photo in item.get("photos", []):
            k = int(np.clip(np.searchsorted(times, photo["time"]), 0, len(times) - 1))
            T = camera_pose(trajectory["north"][k], trajectory["east"][k], trajectory["depth"][k],
                            trajectory["heading"][k], baseline=baseline)
            cams.append(transform_points(invert(truth.T_world_object), T[None, :3, 3])[0])
        if cams:
            c = np.array(cams)
            plan.scatter(c[:, 0], c[:, 1], marker="o", s=25, facecolor="none", edgecolor="tab:orange",
                         label="camera at photos (truth)")
            side.scatter(c[:, 0], -c[:, 2], marker="o", s=25, facecolor="none", edgecolor="tab:orange")
        pad = 4.0
        plan.set_xlim(-pad, L + pad)
        plan.set_ylim(-pad, W + pad)
    plan.set_aspect("equal")
    plan.set_xlabel("object x [m]")
    plan.set_ylabel("object y [m]")
    plan.legend(fontsize=7, loc="upper right")
    ok = item.get("targets_ok", 0)
    plan.set_title(f"{element}: {obj.id}, {ok}/{len(item.get('targets', {}))} targets photographed within bounds")
    side.set_xlabel("object x [m]")
    side.set_ylabel("height above the object origin [m]")
    side.set_title("side view")
    return fig
