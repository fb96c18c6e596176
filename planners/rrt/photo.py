"""Photo survey of a flat object: camera passes that cover its area, denser over informative parts
(seed 002 §2.2.1).

The seed asks for a trajectory that covers the object completely, with a denser net of passes (галсы) over the
most informative areas of the information map, within the vehicle's dynamics and the occupancy map. Here:

* the down-looking camera at `altitude` images a footprint 2·h·tan(fov_h/2) across track (camera x is the
  vehicle's starboard) and 2·h·tan(fov_v/2) along it; passes run along the direction that makes the area
  narrowest across them (fewest turns);
* the pass spacing is the footprint times (1 − overlap), divided by 1 + gain·Î where Î is the highest
  normalised information on the ground between a pass and where the next would be at the plain spacing: the
  spacing never exceeds the overlap spacing
  (full coverage) and shrinks to 1/(1 + gain) of it over the most informative ground;
* passes are flown boustrophedon; the turns between them are OMPL Dubins curves for the turning radius (flown
  at the survey depth), checked against the clearance grid when one is given, and re-planned with RRT*
  (`plan_path`) when a curve is blocked; photographs are triggered along each pass at the along-track footprint
  times (1 − overlap), also divided by 1 + gain·Î.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from planners.rrt import _ompl
from planners.rrt.clearance import ClearanceGrid
from planners.rrt.information import InformationField
from planners.rrt.planning import plan_path

Array = NDArray[np.float64]


@dataclass(frozen=True)
class PhotoSurvey:
    """A photo-survey plan in NED metres."""

    path: Array
    """(K, 3) waypoints: passes and the turns between them (turns sampled ≤ 1 m apart)."""
    passes: list[Array]
    """Each pass as its (2, 3) start and end, in flying order."""
    offsets: Array
    """Across-track offset of each pass (metres from the first), increasing."""
    photo_points: Array
    """(M, 3) positions where photographs are taken."""
    heading_deg: float
    """Direction of the passes (the first one; they alternate)."""
    footprint: tuple[float, float]
    """Camera footprint (across, along track), metres."""
    base_spacing: float
    """Pass spacing over blank ground: footprint across track × (1 − overlap)."""

    @property
    def length(self) -> float:
        return float(np.linalg.norm(np.diff(self.path, axis=0), axis=1).sum()) if len(self.path) > 1 else 0.0


def footprint(altitude: float, fov_deg: tuple[float, float]) -> tuple[float, float]:
    """Across- and along-track footprint of a down-looking camera.

    >>> [round(v, 2) for v in footprint(5.0, (90.0, 60.0))]
    [10.0, 5.77]
    """
    if not altitude > 0:
        raise ValueError(f"altitude must be positive, got {altitude}")
    return (2.0 * altitude * math.tan(math.radians(fov_deg[0]) / 2.0),
            2.0 * altitude * math.tan(math.radians(fov_deg[1]) / 2.0))


def photo_survey_path(area: ArrayLike, information: InformationField, *, altitude: float, depth: float,
                      fov_deg: tuple[float, float] = (60.0, 45.0), overlap: float = 0.6, gain: float = 2.0,
                      heading_deg: float | None = None, turning_radius: float | None = None,
                      clearance: ClearanceGrid | None = None, safety_distance: float = 0.0,
                      seed: int | None = None) -> PhotoSurvey:
    """Passes covering the polygon `area` ([[north, east], …]) with the camera footprint and `overlap` (0–1).

    `depth` is the depth flown (the object's top lies `altitude` below it); `gain` sets how much denser passes
    get over the most informative ground (1 + gain times); `heading_deg` fixes the pass direction (default: the
    one that minimises the across-track width).
    """
    poly = np.asarray(area, dtype=float).reshape(-1, 2)
    if len(poly) < 3:
        raise ValueError("area needs at least three vertices")
    if not 0.0 <= overlap < 1.0:
        raise ValueError(f"overlap must be a fraction in [0, 1), got {overlap}")
    across, along = footprint(altitude, fov_deg)
    base = across * (1.0 - overlap)
    heading = _narrowest_heading(poly) if heading_deg is None else float(heading_deg)
    h = math.radians(heading)
    u_axis, v_axis = np.array([math.cos(h), math.sin(h)]), np.array([-math.sin(h), math.cos(h)])
    uv = np.stack([poly @ u_axis, poly @ v_axis], axis=1)
    v_lo, v_hi = float(uv[:, 1].min()), float(uv[:, 1].max())
    profile_v, profile = _band_information(uv, information, u_axis, v_axis, across)

    def band_max(a: float, b: float) -> float:
        sel = (profile_v >= a) & (profile_v <= b)
        return float(profile[sel].max()) if sel.any() else 0.0

    offsets = [v_lo + min(base, across) / 2.0]
    while offsets[-1] + across / 2.0 < v_hi - 1e-9:
        v = offsets[-1]
        offsets.append(v + base / (1.0 + gain * band_max(v, v + base)))
    passes, photos = [], []
    for k, v in enumerate(offsets):
        u0, u1 = _band_extent(uv, v - across / 2.0, v + across / 2.0)
        if u1 <= u0:
            continue
        ends = [u0, u1] if k % 2 == 0 else [u1, u0]
        p = np.array([[*(u * u_axis + v * v_axis), depth] for u in ends])
        passes.append(p)
        photos.append(_photo_points(p, information, along * (1.0 - overlap), gain))
    path = _join(passes, heading, turning_radius, clearance, safety_distance, seed)
    return PhotoSurvey(path, passes, np.asarray(offsets) - offsets[0], np.concatenate(photos), heading % 360.0,
                       (across, along), base)


def _narrowest_heading(poly: Array) -> float:
    """Pass direction (degrees, 0–180) across which the polygon is narrowest, in 1° steps."""
    angles = np.radians(np.arange(0.0, 180.0, 1.0))
    v = poly @ np.stack([-np.sin(angles), np.cos(angles)])
    return float(np.degrees(angles[np.argmin(v.max(axis=0) - v.min(axis=0))]))


def _band_extent(uv: Array, v0: float, v1: float) -> tuple[float, float]:
    """Along-track extent of the polygon's part between across-track offsets v0 and v1."""
    us = [u for u, v in uv if v0 <= v <= v1]
    for a, b in zip(uv, np.roll(uv, -1, axis=0), strict=True):
        for v in (v0, v1):
            if (a[1] - v) * (b[1] - v) < 0:
                us.append(a[0] + (v - a[1]) / (b[1] - a[1]) * (b[0] - a[0]))
    return (min(us), max(us)) if us else (0.0, -1.0)


def inside_polygon(uv: Array, pts: Array) -> NDArray[np.bool_]:
    """Even-odd point-in-polygon for points (N, 2) in the (u, v) frame."""
    inside = np.zeros(len(pts), dtype=bool)
    for a, b in zip(uv, np.roll(uv, -1, axis=0), strict=True):
        crosses = (a[1] > pts[:, 1]) != (b[1] > pts[:, 1])
        with np.errstate(divide="ignore", invalid="ignore"):
            u_cross = a[0] + (pts[:, 1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0])
        inside ^= crosses & (pts[:, 0] < u_cross)
    return inside


def _band_information(uv: Array, info: InformationField, u_axis: Array, v_axis: Array,
                      across: float) -> tuple[Array, Array]:
    """Highest Î over the area along each across-track offset, every half information cell."""
    step = info.cell / 2.0
    us = np.arange(uv[:, 0].min(), uv[:, 0].max() + step, step)
    vs = np.arange(uv[:, 1].min() - across, uv[:, 1].max() + across + step, step)
    uu, vv = np.meshgrid(us, vs, indexing="ij")
    pts = np.stack([uu.ravel(), vv.ravel()], axis=1)
    ne = pts[:, :1] * u_axis + pts[:, 1:] * v_axis
    values = np.where(inside_polygon(uv, pts), info.normalised_at(ne), 0.0).reshape(uu.shape).max(axis=0)
    return vs, values


def _photo_points(p: Array, info: InformationField, spacing: float, gain: float) -> Array:
    """Trigger points along one pass, closer together where Î is high."""
    length = float(np.linalg.norm(p[1] - p[0]))
    d = (p[1] - p[0]) / length if length > 0 else np.zeros(3)
    s, out = 0.0, [p[0]]
    while s < length:
        here = p[0] + s * d
        s += spacing / (1.0 + gain * float(info.normalised_at(here[None])[0]))
        out.append(p[0] + min(s, length) * d)
    return np.array(out)


def _join(passes: list[Array], heading: float, radius: float | None, grid: ClearanceGrid | None, safety: float,
          seed: int | None) -> Array:
    """Passes linked by turns: Dubins curves (checked against the grid; RRT* when blocked) or straight links."""
    if not passes:
        return np.zeros((0, 3))
    out = [passes[0]]
    for k in range(1, len(passes)):
        a, b = passes[k - 1][1], passes[k][0]
        h_a = heading if (k - 1) % 2 == 0 else heading + 180.0
        h_b = heading if k % 2 == 0 else heading + 180.0
        link = _dubins(a, h_a, b, h_b, radius) if radius is not None else np.stack([a, b])
        if grid is not None and not grid.safe(_dense(link), safety).all():
            planned = plan_path(grid, [*a, h_a], [*b, h_b], safety_distance=safety, planner="RRTstar",
                                time_limit_s=0.5, turning_radius=radius, seed=seed)
            if not planned.solved:
                raise ValueError(f"no safe turn from {a.round(2).tolist()} to {b.round(2).tolist()}")
            link = planned.points
        out.append(link[1:-1])
        out.append(passes[k])
    return np.concatenate(out)


def _dense(points: Array, spacing: float = 0.25) -> Array:
    seg = [points[:1]]
    for a, b in zip(points[:-1], points[1:], strict=True):
        n = max(1, math.ceil(float(np.linalg.norm(b - a)) / spacing))
        seg.append(a + (np.arange(1, n + 1)[:, None] / n) * (b - a))
    return np.concatenate(seg)


def _dubins(a: Array, heading_a: float, b: Array, heading_b: float, radius: float, spacing: float = 1.0) -> Array:
    """The shortest bounded-curvature curve between two poses at one depth (OMPL's Dubins space), sampled."""
    base, _, _ = _ompl.load()
    space = base.DubinsStateSpace(float(radius))
    s0, s1, s = space.allocState(), space.allocState(), space.allocState()
    for st, p, hd in ((s0, a, heading_a), (s1, b, heading_b)):
        st.setX(float(p[0]))
        st.setY(float(p[1]))
        st.setYaw(math.radians(hd))
    n = max(2, math.ceil(space.distance(s0, s1) / spacing) + 1)
    pts = []
    for t in np.linspace(0.0, 1.0, n):
        space.interpolate(s0, s1, float(t), s)
        pts.append((s.getX(), s.getY(), float(a[2] + t * (b[2] - a[2]))))
    return np.asarray(pts)
