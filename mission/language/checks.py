"""Cross-checks of a mission that no single key can make: references between ids, geometry against the
geofence, depths and altitudes against the safety envelope, sensors and plug-ins the route needs.

Every check reports and goes on, so that the designer sees every mistake at once.
"""

from __future__ import annotations

import dataclasses
import difflib
import re
from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np
from shapely.geometry import LineString as ShapelyLine
from shapely.geometry import Point as ShapelyPoint
from shapely.geometry import Polygon as ShapelyPolygon
from shapely.validation import explain_validity

from mission.errors import Diagnostic
from mission.language.actions import check_actions
from mission.language.models import (
    Home,
    Inspect,
    KnownObject,
    Plugins,
    Reference,
    RouteElement,
    Safety,
    Sensors,
    Survey,
    Transit,
    VehicleSettings,
)
from mission.language.source import Located, PathKey
from mission.language.timing import check_timing
from mission.language.viewpoints import forbidden_viewpoints


@dataclass
class Parts:
    """The sections of a mission that validated on their own (others are None or left out)."""

    safety: Safety | None = None
    sensors: Sensors | None = None
    plugins: Plugins | None = None
    home: Home | None = None
    objects: list[tuple[int, KnownObject]] = field(default_factory=list)
    route: list[tuple[int, RouteElement]] = field(default_factory=list)
    raw_object_ids: set[str] = field(default_factory=set)  # ids of objects, even those that did not validate
    vehicle: VehicleSettings | None = None


def _hint(name: str, known: Iterable[str]) -> str:
    close = difflib.get_close_matches(name, list(known), n=1, cutoff=0.6)
    return f"; did you mean '{close[0]}'?" if close else ""


def _duplicates(doc: Located, items: Iterable[tuple[PathKey, str]], what: str, scope: str = ""
                ) -> list[Diagnostic]:
    seen: dict[str, PathKey] = {}
    out = []
    for path, ident in items:
        if ident in seen:
            line, _ = doc.where(seen[ident])
            out.append(doc.diagnostic(path, f"duplicate {what} '{ident}'{scope} (first defined on line {line})"))
        else:
            seen[ident] = path
    return out


def _polygon(doc: Located, path: PathKey, coords: list[tuple[float, float]], what: str
             ) -> tuple[ShapelyPolygon | None, list[Diagnostic]]:
    poly = ShapelyPolygon([(e, n) for n, e in coords])  # x = east, y = north
    if not poly.is_valid:
        reason = explain_validity(poly)
        found = re.search(r"\[([-\d.eE+]+) ([-\d.eE+]+)\]", reason)
        if reason.startswith("Self-intersection"):
            near = f" near (north, east) = ({float(found[2]):.1f}, {float(found[1]):.1f})" if found else ""
            reason = f"it intersects itself{near}"
        return None, [doc.diagnostic(path, f"{what} is not a valid polygon: {reason}")]
    if poly.area <= 0.0:
        return None, [doc.diagnostic(path, f"{what} has no area (its points are collinear or repeated)")]
    return poly, []


def _check_objects(doc: Located, parts: Parts) -> list[Diagnostic]:
    out = _duplicates(doc, [(("objects", i, "id"), o.id) for i, o in parts.objects], "object id")
    for i, obj in parts.objects:
        base: PathKey = ("objects", i)
        sets = obj.characteristic_points
        out += _duplicates(doc, [(base + ("characteristic_points", j, "id"), s.id) for j, s in enumerate(sets)],
                           "point-set id", f" in object '{obj.id}'")
        out += _duplicates(doc, [(base + ("targets", k, "id"), t.id) for k, t in enumerate(obj.targets)],
                           "target id", f" in object '{obj.id}'")
        for j, pset in enumerate(sets):
            where = base + ("characteristic_points", j, "points")
            pts = np.asarray(pset.points, dtype=float).reshape(-1, 3)
            if len(pts) < 3:
                out.append(doc.diagnostic(where, f"point set '{pset.id}' has {len(pts)} point(s); "
                                                 "a set needs at least 3 to fix a pose"))
            elif np.linalg.matrix_rank(pts - pts.mean(axis=0), tol=1e-6) < 2:
                out.append(doc.diagnostic(where, f"the points of set '{pset.id}' are collinear; "
                                                 "they cannot fix a pose"))
        set_ids = [s.id for s in sets]
        for k, target in enumerate(obj.targets):
            if target.reference not in set_ids:
                known = ", ".join(set_ids) or "none"
                out.append(doc.diagnostic(
                    base + ("targets", k, "reference"),
                    f"target '{target.id}' references point set '{target.reference}', which object "
                    f"'{obj.id}' does not have (it has: {known}){_hint(target.reference, set_ids)}"))
    return out


def _check_route(doc: Located, parts: Parts) -> list[Diagnostic]:
    out = _duplicates(doc, [(("route", i, "id"), e.id) for i, e in parts.route], "route element id")
    objects = {o.id: o for _, o in parts.objects}
    sensors, plugins = parts.sensors, parts.plugins
    for i, element in parts.route:
        base: PathKey = ("route", i, element.kind)
        p = element.params
        if isinstance(p, Inspect | Reference) or (element.kind == "explore" and p.object != "detected"):  # type: ignore[union-attr]
            oid = p.object  # type: ignore[union-attr]
            if oid not in objects and oid in parts.raw_object_ids:
                pass  # the object itself is broken; its own diagnostics say why
            elif oid not in objects:
                extra = "" if element.kind == "inspect" else " (or 'detected')"
                out.append(doc.diagnostic(base + ("object",), f"unknown object '{oid}'{extra}; the database has: "
                                          f"{', '.join(objects) or 'none'}{_hint(oid, objects)}"))
            elif isinstance(p, Inspect) and isinstance(p.targets, list):
                names = [t.id for t in objects[oid].targets]
                for k, tid in enumerate(p.targets):
                    if tid not in names:
                        out.append(doc.diagnostic(base + ("targets", k), f"object '{oid}' has no target '{tid}'"
                                                  f"{_hint(tid, names)}"))
            elif isinstance(p, Reference):
                names = [s.id for s in objects[oid].characteristic_points]
                if not names:
                    out.append(doc.diagnostic(base + ("object",), f"object '{oid}' has no characteristic points "
                                                                 "to reference to"))
                for k, sid in enumerate(p.point_sets if isinstance(p.point_sets, list) else []):
                    if sid not in names:
                        out.append(doc.diagnostic(base + ("point_sets", k), f"object '{oid}' has no point set "
                                                                           f"'{sid}'{_hint(sid, names)}"))
        if sensors is not None:
            need = {"survey": getattr(p, "sensor", None), "explore": getattr(p, "sensor", None),
                    "inspect": "stereo", "reference": "stereo"}.get(element.kind)
            if isinstance(p, Transit) and p.navigation == "usbl":
                need = "usbl"
            if need and getattr(sensors, need) is None:
                key = ("navigation",) if need == "usbl" else (("sensor",) if element.kind in ("survey", "explore")
                                                              else ())
                out.append(doc.diagnostic(base + key, f"route element '{element.id}' needs the '{need}' sensor, "
                                                      f"which `sensors` does not configure"))
        if isinstance(p, Inspect | Reference) and plugins is not None and plugins.referencing is None:
            out.append(doc.diagnostic(base, f"{element.kind} of '{p.object}' needs a referencing plug-in; "
                                            "name one under plugins.referencing"))
    return out


def _check_envelope(doc: Located, parts: Parts) -> list[Diagnostic]:
    out: list[Diagnostic] = []
    safety = parts.safety
    fence = None
    if safety is not None and safety.geofence is not None:
        fence, errs = _polygon(doc, ("safety", "geofence"), safety.geofence, "the geofence")
        out += errs
    max_depth = safety.max_depth if safety else None
    min_alt = safety.min_altitude if safety else None

    def inside(path: PathKey, north: float, east: float, what: str) -> None:
        if fence is not None and not fence.covers(ShapelyPoint(east, north)):
            out.append(doc.diagnostic(path, f"{what} ({north:g}, {east:g}) lies outside the geofence"))

    def depth_ok(path: PathKey, depth: float | None, what: str) -> None:
        if depth is not None and max_depth is not None and depth > max_depth:
            out.append(doc.diagnostic(path, f"{what} {depth:g} m is beyond safety.max_depth {max_depth:g} m"))

    def altitude_ok(path: PathKey, altitude: float | None, what: str) -> None:
        if altitude is not None and min_alt is not None and altitude < min_alt:
            out.append(doc.diagnostic(path, f"{what} {altitude:g} m is below safety.min_altitude {min_alt:g} m"))

    if parts.home is not None:
        inside(("home",), parts.home.north, parts.home.east, "home")
        depth_ok(("home", "depth"), parts.home.depth, "home depth")
    if safety is not None and not isinstance(safety.on_violation.abort_to, str):
        a = safety.on_violation.abort_to
        inside(("safety", "on_violation", "abort_to"), a.north, a.east, "the abort point")
        depth_ok(("safety", "on_violation", "abort_to", "depth"), a.depth, "abort depth")
    for i, element in parts.route:
        base: PathKey = ("route", i, element.kind)
        p = element.params
        if isinstance(p, Transit):
            if not isinstance(p.to, str):
                inside(base + ("to",), p.to.north, p.to.east, f"transit point of '{element.id}'")
            depth_ok(base + ("depth",), p.depth, f"depth of '{element.id}'")
            altitude_ok(base + ("altitude",), p.altitude, f"altitude of '{element.id}'")
        elif isinstance(p, Survey):
            altitude_ok(base + ("altitude",), p.altitude, f"survey altitude of '{element.id}'")
            area, errs = _polygon(doc, base + ("area",), p.area, f"the survey area of '{element.id}'")
            out += errs
            for k, zone in enumerate(p.exclude):
                _, errs = _polygon(doc, base + ("exclude", k), zone, f"no-go zone {k + 1} of '{element.id}'")
                out += errs
            if area is not None and fence is not None and not fence.covers(area):
                out.append(doc.diagnostic(base + ("area",), f"the survey area of '{element.id}' extends outside "
                                                            "the geofence"))
    if fence is not None:
        out += _legs_outside(doc, parts, fence)
    return out


def _legs_outside(doc: Located, parts: Parts, fence: ShapelyPolygon) -> list[Diagnostic]:
    """Straight transit legs between points the mission fixes (home, then each transit's point; a survey,
    exploration or inspection ends where the route does not say) that leave a non-convex geofence although both
    ends lie inside it."""
    out: list[Diagnostic] = []
    home = (parts.home.north, parts.home.east) if parts.home is not None else None
    here = home
    for i, element in parts.route:
        p = element.params
        if not isinstance(p, Transit):
            here = None
            continue
        goal = home if isinstance(p.to, str) else (p.to.north, p.to.east)
        if here is not None and goal is not None and here != goal:
            a, b = ShapelyPoint(here[1], here[0]), ShapelyPoint(goal[1], goal[0])
            if fence.covers(a) and fence.covers(b) and not fence.covers(ShapelyLine([a, b])):
                d = doc.diagnostic(("route", i, "transit", "to"),
                                   f"the leg of '{element.id}' from ({here[0]:g}, {here[1]:g}) to "
                                   f"({goal[0]:g}, {goal[1]:g}) crosses outside the geofence: the vehicle will "
                                   "abort there")
                out.append(dataclasses.replace(d, warning=True))
        here = goal
    return out


def _check_viewpoints(doc: Located, parts: Parts) -> list[Diagnostic]:
    """Warnings for target viewpoints that the database shows below the minimum altitude (`viewpoints`)."""
    if parts.safety is None:
        return []
    return [dataclasses.replace(doc.diagnostic(("objects", i, "targets", k), message), warning=True)
            for i, obj in parts.objects
            for k, message in forbidden_viewpoints(obj, parts.safety.min_altitude)]


def cross_check(doc: Located, parts: Parts) -> list[Diagnostic]:
    """Every cross-section problem of a mission whose sections validated (fully or partly)."""
    return (_check_objects(doc, parts) + _check_route(doc, parts) + _check_envelope(doc, parts)
            + _check_viewpoints(doc, parts) + check_timing(doc, parts)
            + check_actions(doc, parts.route, parts.sensors))
