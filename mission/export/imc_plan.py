"""IMC `PlanSpecification` of the plannable route (`mission.export.plan`) for LSTS vehicles (DUNE, Neptus), built
and serialised with imcpy: a transit is a `Goto`, a survey a `FollowPath`, chained by `ManeuverIsDone`
transitions in route order.

IMC positions are WGS84 radians; `z` is a depth (`ZUnits.DEPTH`) or an altitude above the seabed
(`ZUnits.ALTITUDE`). A `FollowPath` holds its first waypoint as the reference and every waypoint as a
`PathPoint` offset (north, east, down metres) in the tangent frame at that reference, as IMC defines it.
`read_imc_plan` reads the bytes back to local (north, east) points of the mission's frame.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from mission.errors import AuvError
from mission.export.plan import Leg
from mission.geodesy import geodetic_to_ned, ned_to_geodetic

TIMEOUT_S = 3600  # per maneuver: a vehicle gives up on a maneuver that takes longer


def _imcpy() -> Any:
    try:
        import imcpy
    except ImportError as exc:
        raise AuvError("IMC plans need imcpy: pip install 'auv-mission[interop]'") from exc
    return imcpy


@dataclass(frozen=True)
class ImcManeuver:
    """A maneuver of a plan read back: its id, type, points in the mission's local frame, z and its units."""

    maneuver_id: str
    kind: str
    points_ne: tuple[tuple[float, float], ...]
    z: float
    z_units: str
    speed: float


def _z(leg: Leg, imc: Any) -> tuple[float, int]:
    if leg.altitude is not None:
        return leg.altitude, imc.ZUnits.ALTITUDE
    return leg.depth or 0.0, imc.ZUnits.DEPTH


def _maneuver(leg: Leg, lat0: float, lon0: float, imc: Any) -> Any:
    z, units = _z(leg, imc)
    lats, lons = ned_to_geodetic([p[0] for p in leg.points_ne], [p[1] for p in leg.points_ne], lat0, lon0)
    if len(leg.points_ne) == 1:
        m = imc.Goto()
        m.lat, m.lon = math.radians(float(lats[0])), math.radians(float(lons[0]))
    else:
        m = imc.FollowPath()
        ref_lat, ref_lon = float(lats[0]), float(lons[0])
        m.lat, m.lon = math.radians(ref_lat), math.radians(ref_lon)
        north, east = geodetic_to_ned(lats, lons, ref_lat, ref_lon)
        for n, e in zip(north, east, strict=True):
            p = imc.PathPoint()
            p.x, p.y, p.z = float(n), float(e), 0.0
            m.points.append(p)
    m.z, m.z_units = float(z), units
    m.speed, m.speed_units = float(leg.speed), imc.SpeedUnits.METERS_PS
    m.timeout = TIMEOUT_S
    return m


def imc_plan(legs: Sequence[Leg], lat0: float, lon0: float, plan_id: str, description: str = "") -> Any:
    """The imcpy `PlanSpecification` of the legs, one maneuver per leg, named after its route element."""
    imc = _imcpy()
    plan = imc.PlanSpecification()
    plan.plan_id, plan.description = plan_id, description
    for k, leg in enumerate(legs):
        pm = imc.PlanManeuver()
        pm.maneuver_id = leg.element
        pm.data = _maneuver(leg, lat0, lon0, imc)
        plan.maneuvers.append(pm)
        if k:
            tr = imc.PlanTransition()
            tr.source_man, tr.dest_man, tr.conditions = legs[k - 1].element, leg.element, "ManeuverIsDone"
            plan.transitions.append(tr)
    plan.start_man_id = legs[0].element if legs else ""
    return plan


def imc_plan_bytes(legs: Sequence[Leg], lat0: float, lon0: float, plan_id: str, description: str = "") -> bytes:
    """The plan as an IMC packet (header, fields, footer with CRC), as a vehicle receives it."""
    return bytes(_imcpy().Packet.serialize(imc_plan(legs, lat0, lon0, plan_id, description)))


def read_imc_plan(data: bytes, lat0: float, lon0: float) -> tuple[str, list[ImcManeuver]]:
    """The plan id and maneuvers (in transition order) of an IMC PlanSpecification packet, in the local frame."""
    imc = _imcpy()
    try:
        plan = imc.Packet.deserialize(data)
    except Exception as exc:  # imcpy raises its own C++-bound errors on a bad packet
        raise AuvError(f"not an IMC packet ({exc})") from exc
    if not isinstance(plan, imc.PlanSpecification):
        raise AuvError(f"not an IMC PlanSpecification (found {type(plan).__name__})")
    units = {imc.ZUnits.DEPTH: "depth", imc.ZUnits.ALTITUDE: "altitude"}
    found = []
    for pm in plan.maneuvers:
        m = pm.data
        lat, lon = math.degrees(m.lat), math.degrees(m.lon)
        if isinstance(m, imc.FollowPath):
            offsets = [(p.x, p.y) for p in m.points]
            lats, lons = ned_to_geodetic([o[0] for o in offsets], [o[1] for o in offsets], lat, lon)
        else:
            lats, lons = np.array([lat]), np.array([lon])
        north, east = geodetic_to_ned(lats, lons, lat0, lon0)
        points = tuple((float(n), float(e)) for n, e in zip(north.reshape(-1), east.reshape(-1), strict=True))
        found.append(ImcManeuver(pm.maneuver_id, type(m).__name__, points, float(m.z),
                                 units.get(m.z_units, str(m.z_units)), float(m.speed)))
    order = {mv.maneuver_id: mv for mv in found}
    chain = [plan.start_man_id] if plan.start_man_id in order else []
    nxt = {t.source_man: t.dest_man for t in plan.transitions}
    while chain and chain[-1] in nxt and nxt[chain[-1]] in order and nxt[chain[-1]] not in chain:
        chain.append(nxt[chain[-1]])
    return str(plan.plan_id), [order[c] for c in chain] if len(chain) == len(found) else found
