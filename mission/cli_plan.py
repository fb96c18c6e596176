"""`auv plan MISSION` and `auv validate --estimate`: the distance, duration, energy and survey coverage a mission
will take, per element and in total, before the dive (`mission.estimate`), and a figure of the planned paths."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from mission.errors import MissionError

if TYPE_CHECKING:
    from mission.estimate import MissionEstimate
    from mission.language.models import Mission


def mission_estimate(mission: Mission) -> tuple[MissionEstimate, list[tuple[str, str]]]:
    """The estimate of the route as the strategic level plans it before the dive, and the work it drops."""
    from mission.estimate import RouteEstimator, estimate_mission
    from mission.strategy import Budget, plan_route

    chart = None
    if mission.world is not None:
        from mission.world.chart import chart_of

        chart = chart_of(mission.world)
    estimator = RouteEstimator(mission, chart)
    home = mission.home
    plan = plan_route(mission, mission.route, Budget(home.north, home.east, home.depth), estimator)
    return estimate_mission(mission, plan.order, estimator), [(e.id, why) for e, why in plan.dropped]


def print_estimate(mission: Mission, as_json: bool, out: Any = None) -> None:
    out = out or sys.stdout
    estimate, dropped = mission_estimate(mission)
    if as_json:
        data = estimate.as_json()
        data["order"] = [e.id for e in estimate.elements]
        data["dropped"] = [{"element": ident, "reason": why} for ident, why in dropped]
        print(json.dumps(data, indent=1), file=out)
        return
    print(f"  {'element':<24} {'kind':<9} {'distance':>10} {'duration':>10} {'energy':>9}  basis", file=out)
    for e in estimate.elements:
        cover = f", coverage {e.coverage_percent:.2f} %" if e.coverage_percent is not None else ""
        print(f"  {e.id:<24} {e.kind:<9} {e.distance_m:8.0f} m {e.duration_s / 60:6.1f} min {e.energy_wh:6.1f} Wh"
              f"  {e.basis}{cover}", file=out)
    print(f"  {'total':<34} {estimate.distance_m:8.0f} m {estimate.duration_s / 60:6.1f} min "
          f"{estimate.energy_wh:6.1f} Wh", file=out)
    listed = [e.id for e in mission.route if all(e.id != d for d, _ in dropped)]
    if [e.id for e in estimate.elements] != listed:
        print(f"  order: {', '.join(e.id for e in estimate.elements)} (the strategic level's)", file=out)
    for ident, why in dropped:
        print(f"  dropped: {ident} ({why})", file=out)
    for warning in estimate.warnings:
        print(f"  warning: {warning}", file=out)


def _plan(args: argparse.Namespace) -> int:
    from mission.language import validate_mission_file

    mission, diags = validate_mission_file(args.mission)
    if mission is None:
        raise MissionError([d for d in diags if not d.warning])
    for d in diags:
        print(d, file=sys.stderr)
    if not args.json:
        print(f"{mission.name}: estimate before the dive")
    print_estimate(mission, args.json)
    if args.figure:
        plot_plan(mission, mission_estimate(mission)[0], Path(args.figure))
        print(f"figure: {args.figure}", file=sys.stderr if args.json else sys.stdout)
    return 0


def plot_plan(mission: Mission, estimate: MissionEstimate, path: Path) -> None:
    """The planned paths over the site: the geofence, survey areas and their zones, database objects."""
    from mission.extras import require

    require("matplotlib", "the plan's figure (`auv plan --figure`)")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 7))
    fence = mission.safety.geofence
    if fence is not None:
        ring = [*fence, fence[0]]
        ax.plot([p[1] for p in ring], [p[0] for p in ring], color="tab:red", lw=1, label="geofence")
    for element in mission.route:
        if element.survey is not None:
            ring = [*element.survey.area, element.survey.area[0]]
            ax.fill([p[1] for p in ring], [p[0] for p in ring], color="tab:blue", alpha=0.08)
            for zone in element.survey.exclude:
                ax.fill([p[1] for p in zone], [p[0] for p in zone], color="0.5", alpha=0.5)
    for e in estimate.elements:
        if e.path:
            ax.plot([p[1] for p in e.path], [p[0] for p in e.path], lw=0.8, label=f"{e.id} ({e.kind})")
    for obj in mission.objects:
        ax.plot(obj.pose.east, obj.pose.north, "k^", ms=6)
        ax.annotate(obj.id, (obj.pose.east, obj.pose.north), fontsize=7, xytext=(3, 3), textcoords="offset points")
    ax.plot(mission.home.east, mission.home.north, "ko", ms=5)
    ax.set_aspect("equal")
    ax.set_xlabel("east (m)")
    ax.set_ylabel("north (m)")
    ax.set_title(f"{mission.name}: {estimate.distance_m:.0f} m, {estimate.duration_s / 60:.0f} min, "
                 f"{estimate.energy_wh:.0f} Wh (estimated)")
    ax.legend(fontsize=7, loc="best")
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120, bbox_inches="tight")
    plt.close(fig)


def add_plan_commands(sub: Any) -> None:
    p = sub.add_parser("plan", help="estimate a mission's distance, duration, energy and coverage before the dive")
    p.add_argument("mission", help="mission YAML file")
    p.add_argument("--json", action="store_true", help="the estimate as JSON")
    p.add_argument("--figure", metavar="PNG", help="draw the planned paths over the site")
    p.set_defaults(func=_plan)
