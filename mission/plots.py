"""Figures of a run folder, drawn from its files alone (`auv plot DIR`; `auv simulate` draws them at the end).

    map.png          seabed, geofence, survey areas and no-go zones, charted and true objects, planned paths,
                     true and estimated tracks, USBL fixes and safety violations, in plan view
    profile.png      true and measured depth over the seabed under the vehicle, and altitude, per element
    navigation.png   horizontal navigation error against the filter's σ, with dead-reckoning spans and fixes
    survey_ID.png    per survey element: sensed depth and passes, information map, detections over the truth
    explore_ID.png   per explore element: voxel model, views and path (plan, elevation), explored volume over time
    photos_ID.png    per photo-survey explore element: passes, photo points and footprints over the object
    inspect_ID.png   per inspect element: sets, targets, the (re-)planned order and the flown path in the object
                     frame, with the camera's true position at each photograph

Plan views draw east to the right and north up at equal scale; depth axes grow downwards.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from mission.errors import MissionError
from mission.frames import pose_matrix, transform_points
from mission.language.loader import load_world
from mission.language.models import KnownObject, Mission
from mission.runfolder import RunData, read_run_folder
from mission.survey_plots import survey_figure
from mission.world.scene import Scene, build_scene

TRUE_COLOR, EST_COLOR, PLAN_COLOR = "black", "tab:orange", "tab:purple"
DB_COLOR, OBJ_COLOR, FENCE_COLOR, AREA_COLOR = "tab:blue", "saddlebrown", "darkred", "teal"
BAND_COLOR, DR_COLOR = "0.92", "khaki"
DPI = 120


def plot_run(folder: Path, out_dir: Path | None = None) -> list[Path]:
    """Draw a run folder's figures into `out_dir` (default `folder/plots/`) and return their paths."""
    run = read_run_folder(folder)
    out = Path(out_dir) if out_dir is not None else Path(folder) / "plots"
    out.mkdir(parents=True, exist_ok=True)
    scene = _load_scene(run.mission)
    drawers: list[tuple[str, Callable[[], Figure]]] = [
        ("map.png", lambda: _map_figure(run, scene)),
        ("profile.png", lambda: _profile_figure(run)),
        ("navigation.png", lambda: _navigation_figure(run)),
    ]
    for element, products in run.maps.items():
        if "info" in products:
            drawers.append((f"survey_{element}.png", _survey_drawer(run, element, products, scene)))
        if "explore_views" in products or "photo_index" in products:
            prefix = "explore" if "explore_views" in products else "photos"
            drawers.append((f"{prefix}_{element}.png", _explore_drawer(run, element, products, scene)))
    for item in run.metrics.get("elements", []):
        if item.get("kind") == "inspect" and item.get("object"):
            drawers.append((f"inspect_{item['id']}.png", _inspect_drawer(run, item, scene)))
    paths = []
    for name, draw in drawers:
        draw().savefig(out / name, dpi=DPI)  # a bare Figure: no pyplot state, no global backend change
        paths.append(out / name)
    return paths


def _explore_drawer(run: RunData, element: str, products: dict[str, np.ndarray], scene: Scene | None
                    ) -> Callable[[], Figure]:
    from mission.explore_plots import explore_figure, photo_figure

    item: dict[str, Any] = next((e for e in run.metrics.get("elements", []) if e.get("id") == element), {})
    draw = explore_figure if "explore_views" in products else photo_figure
    return lambda: draw(element, products, item, scene)


def _inspect_drawer(run: RunData, item: dict[str, Any], scene: Scene | None) -> Callable[[], Figure]:
    from mission.inspect_plots import inspect_figure

    return lambda: inspect_figure(item["id"], item, run.mission, run.trajectory, run.elements, scene)


def _survey_drawer(run: RunData, element: str, products: dict[str, np.ndarray], scene: Scene | None
                   ) -> Callable[[], Figure]:
    item: dict[str, Any] = next((e for e in run.metrics.get("elements", []) if e.get("id") == element), {})
    return lambda: survey_figure(element, products, item, scene)


# -- reading -------------------------------------------------------------------------------------------------
def _load_scene(mission: Mission) -> Scene | None:
    """The run's world made concrete, or None if there is none to draw (no world, or it cannot be read)."""
    if mission.world is None or not Path(mission.world).is_file():
        return None
    try:
        return build_scene(load_world(mission.world))
    except MissionError:
        return None


def _status(run: RunData) -> str:
    m = run.metrics
    if m.get("completed"):
        return "completed"
    if m.get("aborted"):
        return f"ABORTED ({m['abort_reason']})" if m.get("abort_reason") else "ABORTED"
    return "not completed"


def _events(run: RunData, kind: str) -> list[dict[str, Any]]:
    return [e for e in run.events if e.get("event") == kind]


def _element_spans(time: np.ndarray, elements: Sequence[str]) -> list[tuple[str, float, float]]:
    """(element id, start, end) for each run of equal ids in the trajectory's element column."""
    spans: list[tuple[str, float, float]] = []
    for k, (t, element) in enumerate(zip(time, elements, strict=False)):
        if spans and spans[-1][0] == element:
            spans[-1] = (element, spans[-1][1], float(t))
        else:
            start = float(time[k - 1]) if k > 0 else float(t)
            spans.append((element, start, float(t)))
    return spans


def _dead_reckoning_spans(run: RunData, t_end: float) -> list[tuple[float, float]]:
    """Time spans of elements run without USBL aiding (declared dead-reckoning, or no USBL on board)."""
    no_usbl = run.mission.sensors.usbl is None
    ends: dict[str, list[float]] = {}
    for e in run.events:
        if e.get("event") in ("element_finished", "element_failed"):
            ends.setdefault(str(e.get("element")), []).append(float(e["time"]))
    spans = []
    for e in _events(run, "element_started"):
        if no_usbl or e.get("navigation") == "dead-reckoning":
            t0 = float(e["time"])
            later = [t for t in ends.get(str(e.get("element")), []) if t >= t0]
            spans.append((t0, min(later) if later else t_end))
    return spans


def _charted_outline(obj: KnownObject) -> np.ndarray:
    """(north, east) corners of a database object's length × width rectangle; origin at the pose corner,
    x along the heading, y 90° clockwise from it."""
    length, width, _ = obj.size
    corners = np.array([[0, 0, 0], [length, 0, 0], [length, width, 0], [0, width, 0], [0, 0, 0]], dtype=float)
    T = pose_matrix(obj.pose.north, obj.pose.east, obj.pose.depth, obj.pose.heading)
    return transform_points(T, corners)[:, :2]


# -- map -----------------------------------------------------------------------------------------------------
def _ring(points: Sequence[Sequence[float]]) -> tuple[np.ndarray, np.ndarray]:
    """East and north of a closed [[north, east], ...] ring."""
    p = np.asarray(points, dtype=float).reshape(-1, 2)
    p = np.vstack([p, p[:1]])
    return p[:, 1], p[:, 0]


def _draw_seabed(fig: Figure, ax: Axes, scene: Scene) -> None:
    north, east = scene.seabed.grid()
    shaded = ax.contourf(east, north, scene.seabed.depth, levels=24, cmap="Blues", alpha=0.85, zorder=0)
    ax.contour(east, north, scene.seabed.depth, levels=12, colors="white", linewidths=0.4, alpha=0.6)
    bar = fig.colorbar(shaded, ax=ax, shrink=0.8, pad=0.02)
    bar.set_label("seabed depth [m]")
    bar.ax.invert_yaxis()


def _draw_areas(ax: Axes, mission: Mission) -> None:
    fence = mission.safety.geofence
    if fence:
        ax.plot(*_ring(fence), color=FENCE_COLOR, lw=1.6, ls="-.", label="geofence")
    areas = [e.survey for e in mission.route if e.survey is not None]
    for k, survey in enumerate(areas):
        ax.plot(*_ring(survey.area), color=AREA_COLOR, lw=1.4, label="survey area" if k == 0 else None)
    zones = [z for s in areas for z in s.exclude]
    for k, zone in enumerate(zones):
        ax.fill(*_ring(zone), facecolor="none", edgecolor=FENCE_COLOR, hatch="///", lw=1.0,
                label="no-go zone" if k == 0 else None)


def _label(ax: Axes, east: float, north: float, text: str, color: str, dy: float) -> None:
    ax.annotate(text, (east, north), xytext=(6, dy), textcoords="offset points", fontsize=8, color=color,
                bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.7})


def _draw_objects(ax: Axes, mission: Mission, scene: Scene | None) -> None:
    for k, obj in enumerate(mission.objects):
        ne = _charted_outline(obj)
        ax.plot(ne[:, 1], ne[:, 0], color=DB_COLOR, ls="--", lw=1.2, label=None if k else "charted object")
        _label(ax, ne[:, 1].max(), ne[:, 0].max(), f"{obj.id} (charted)", DB_COLOR, 6)
    for k, placed in enumerate(scene.objects if scene is not None else ()):
        east, north = placed.footprint.exterior.xy  # scene footprints are (x = east, y = north)
        ax.fill(east, north, facecolor=OBJ_COLOR, edgecolor="black", lw=0.8, alpha=0.8,
                label="true object" if k == 0 else None)
        _label(ax, max(east), min(north), placed.id, OBJ_COLOR, -12)


def _draw_tracks(ax: Axes, run: RunData) -> None:
    tr = run.trajectory
    for k, e in enumerate(_events(run, "element_started")):
        path = np.asarray(e.get("planned_path") or [], dtype=float).reshape(-1, 2)
        if len(path):
            ax.plot(path[:, 1], path[:, 0], color=PLAN_COLOR, ls="--", lw=0.9,
                    label="planned path" if k == 0 else None)
    ax.plot(tr["east"], tr["north"], color=TRUE_COLOR, lw=1.4, label="true track")
    ax.plot(tr["east_est"], tr["north_est"], color=EST_COLOR, lw=1.1, label="estimated track")
    fx = run.fixes
    if fx and len(fx.get("time", ())):
        used, accepted = fx["used"] > 0, fx["accepted"] > 0
        ok, bad = used & accepted, used & ~accepted
        ax.plot(fx["east"][ok], fx["north"][ok], ".", color="tab:green", ms=3, label="USBL fix")
        if bad.any():
            ax.plot(fx["east"][bad], fx["north"][bad], "x", color="magenta", ms=5, label="USBL fix rejected")
    for k, v in enumerate(_events(run, "safety_violation")):
        if v.get("north") is None or v.get("east") is None:
            continue
        ax.plot(v["east"], v["north"], "o", color="red", mec="black", ms=7, zorder=5,
                label="safety violation" if k == 0 else None)
        _label(ax, v["east"], v["north"], str(v.get("monitor", "violation")), "red", 8)


def _map_limits(ax: Axes, run: RunData) -> None:
    """Frame the mission (fence, areas, objects, tracks), not the whole seabed grid."""
    m, tr = run.mission, run.trajectory
    pts = [np.column_stack([tr["north"], tr["east"]]), np.array([[m.home.north, m.home.east]])]
    pts += [np.asarray(m.safety.geofence or np.zeros((0, 2)), dtype=float).reshape(-1, 2)]
    pts += [np.asarray(e.survey.area, dtype=float) for e in m.route if e.survey is not None]
    pts += [_charted_outline(o) for o in m.objects]
    ne = np.vstack(pts)
    ne = ne[np.all(np.isfinite(ne), axis=1)]
    lo, hi = ne.min(axis=0), ne.max(axis=0)
    pad = max(0.05 * float((hi - lo).max()), 10.0)
    ax.set_xlim(lo[1] - pad, hi[1] + pad)
    ax.set_ylim(lo[0] - pad, hi[0] + pad)


def _map_figure(run: RunData, scene: Scene | None) -> Figure:
    fig = Figure(figsize=(10, 8.5), layout="constrained")
    ax = fig.subplots()
    if scene is not None:
        _draw_seabed(fig, ax, scene)
    _draw_areas(ax, run.mission)
    _draw_objects(ax, run.mission, scene)
    _draw_tracks(ax, run)
    home = run.mission.home
    ax.plot(home.east, home.north, "*", color="gold", mec="black", ms=14, zorder=6, label="home")
    _map_limits(ax, run)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("east [m]")
    ax.set_ylabel("north [m]")
    ax.set_title(f"{run.mission.name}: {_status(run)}")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.legend(loc="upper left", fontsize=8, framealpha=0.85)
    return fig


# -- time series ---------------------------------------------------------------------------------------------
def _element_bands(axes: Sequence[Axes], run: RunData) -> None:
    """Alternate light bands per route element, labelled with its id at the top of the first axes."""
    for k, (element, t0, t1) in enumerate(_element_spans(run.trajectory["time"], run.elements)):
        for ax in axes:
            if k % 2 == 0:
                ax.axvspan(t0, t1, color=BAND_COLOR, zorder=0, lw=0)
        axes[0].text(0.5 * (t0 + t1), 1.01, element, transform=axes[0].get_xaxis_transform(), ha="center",
                     va="bottom", fontsize=8, clip_on=False)


def _profile_figure(run: RunData) -> Figure:
    tr, safety = run.trajectory, run.mission.safety
    t = tr["time"]
    fig = Figure(figsize=(11, 7), layout="constrained")
    top, bottom = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [3, 2]})
    seabed = tr["depth"] + tr["altitude"]
    top.plot(t, seabed, color=OBJ_COLOR, lw=1.2, label="bottom under vehicle (seabed or object top)")
    if len(t):
        floor = np.nanmax(seabed) + 2.0 if np.isfinite(seabed).any() else 1.0
        top.fill_between(t, seabed, floor, color="tan", alpha=0.5, lw=0)
    top.plot(t, tr["depth"], color=TRUE_COLOR, lw=1.4, label="depth (true)")
    top.plot(t, tr["depth_est"], color=EST_COLOR, lw=1.0, ls="--", label="depth (measured)")
    top.invert_yaxis()
    top.set_ylabel("depth [m]")
    top.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)

    bottom.plot(t, tr["altitude"], color=TRUE_COLOR, lw=1.4, label="altitude (true)")
    est = tr["altitude_est"]
    if np.isfinite(est).any():
        bottom.plot(t, est, color=EST_COLOR, lw=1.0, ls="--", label="altitude (measured)")
    bottom.axhline(safety.min_altitude, color="red", ls="--", lw=1.0,
                   label=f"min altitude {safety.min_altitude:g} m")
    bottom.set_ylim(bottom=0.0)
    bottom.set_ylabel("altitude [m]")
    bottom.set_xlabel("time [s]")
    bottom.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    _element_bands([top, bottom], run)
    for ax in (top, bottom):
        ax.grid(True, lw=0.3, alpha=0.5)
    fig.suptitle(f"{run.mission.name}: depth and altitude — {_status(run)}")
    return fig


def _navigation_figure(run: RunData) -> Figure:
    tr = run.trajectory
    t = tr["time"]
    err = np.hypot(tr["north_est"] - tr["north"], tr["east_est"] - tr["east"])
    sigma = tr["position_sigma"]
    fig = Figure(figsize=(11, 4.8), layout="constrained")
    ax = fig.subplots()
    for k, (t0, t1) in enumerate(_dead_reckoning_spans(run, float(t[-1]) if len(t) else 0.0)):
        ax.axvspan(t0, t1, color=DR_COLOR, alpha=0.5, lw=0, zorder=0, label=None if k else "dead reckoning")
    ax.fill_between(t, 0.0, sigma, color="tab:blue", alpha=0.15, lw=0)
    ax.plot(t, sigma, color="tab:blue", lw=1.0, label="filter 1σ (per axis)")
    ax.plot(t, 3.0 * sigma, color="tab:blue", lw=1.0, ls="--", label="filter 3σ")
    ax.plot(t, err, color=TRUE_COLOR, lw=1.3, label="|estimate − truth| (horizontal)")
    fx = run.fixes
    if fx and len(fx.get("time", ())):
        rug = ax.get_xaxis_transform()
        groups = [(fx["used"] > 0) & (fx["accepted"] > 0), (fx["used"] > 0) & (fx["accepted"] <= 0),
                  fx["used"] <= 0]
        styles = (("tab:green", "accepted"), ("magenta", "rejected"), ("0.6", "unused: not aiding"))
        for mask, (color, name) in zip(groups, styles, strict=True):
            if mask.any():
                ax.vlines(fx["time"][mask], 0.0, 0.05, transform=rug, color=color, lw=1.0,
                          label=f"USBL fix {name}")
    _element_bands([ax], run)
    ax.set_ylim(bottom=0.0)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("horizontal position error [m]")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    fig.suptitle(f"{run.mission.name}: navigation — {_status(run)}")
    return fig
