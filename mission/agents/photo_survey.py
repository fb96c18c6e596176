"""The photo survey of a flat object (seed 002 §2.2.1), the `explore` element with `planner: rrt-photo`.

For each target, the down-looking stereo camera photographs the object's area (its footprint plus `MARGIN_M`)
along `planners.rrt.informative_survey_path`: a receding-horizon RIG tree over the survey's information map
(Î over the area floored at `COVERAGE_FLOOR`, so all of it is worth a photograph and its informative parts
several), Dubins curves for the turning radius checked against the occupancy map seeded from the survey's height
map, from the area's corner nearest the vehicle on the heading it arrives with, until at most `ENOUGH` of the
area's information is unrevealed. Its path budget is the length of the spacing-scaled lawnmower over the same area
(`planners.rrt.photo_survey_path`), capped by `BUDGET_SHARE` of the element's time budget at the survey speed;
the lawnmower is flown instead when the RIG finds no clear way from its start. The camera flies `safe_distance +
NAV_MARGIN_M` above the object's top (within the stereo range); photographs are triggered at the plan's photo points
when the element has the `photograph` action (without it the plan is flown and no photograph is taken, as for a
`model` recording of the area): the agent switches the camera on, takes the first pair that arrives with the
*estimated* pose, and switches it off; a photo point the vehicle passes without coming near is given up once the
path follower is `SKIP_LEGS` legs past it. `photo_coverage_percent` is the share of the object's area inside the
union of the photographs' footprints, placed at their estimated poses. The pairs go into `Knowledge.maps` and
`mission.sim.photos` writes them into the run folder (`photos/`) with their estimated and true poses; the
information map of each target's plan goes into the element's maps (`photo_info_K`, `photo_info_grid_K`: north0,
east0, cell).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import shapely
from shapely.geometry import Polygon

from mission.agents.base import AgentContext
from mission.agents.explore_region import Target, prior_map, survey_map_for
from mission.agents.report import ExploredObject, ExploreReport
from mission.agents.waypoints import PathFollower
from mission.vehicle import Command, Observation
from planners.rrt import (
    ClearanceGrid,
    InformationField,
    InformativeSurvey,
    PhotoSurvey,
    informative_survey_path,
    photo_survey_path,
)

MARGIN_M = 1.0
NAV_MARGIN_M = 1.0
OVERLAP = 0.6
GAIN = 2.0
SURVEY_SPEED = 0.5  # m/s over the object: slow enough for sharp photographs
TRIGGER_M = 0.6
BUDGET_SHARE = 0.7  # of the element's time budget flown surveying (the rest: approaches and climbing away)
COVERAGE_FLOOR = 0.2  # Î over the object's area is at least this: all of it is worth a photograph
ENOUGH = 0.02  # ends when 98 % is revealed: repeated photographs, informative ground first, keep the coverage
MIN_RADIUS_M = 1.0  # the Dubins radius used when the vehicle declares no turning radius
SKIP_LEGS = 4  # a photo point whose path point lies this many legs behind the follower's is given up


def footprint_polygon(north: float, east: float, heading_deg: float, across: float, along: float) -> Polygon:
    """The camera footprint on the ground (x = east, y = north): `across` to starboard, `along` fore–aft."""
    h = math.radians(heading_deg)
    fwd, stb = np.array([math.cos(h), math.sin(h)]), np.array([-math.sin(h), math.cos(h)])
    corners = [np.array([north, east]) + a * along / 2 * fwd + b * across / 2 * stb
               for a, b in ((1, 1), (1, -1), (-1, -1), (-1, 1))]
    return Polygon([(c[1], c[0]) for c in corners])


def target_area(t: Target, margin: float) -> np.ndarray:
    """The target's footprint rectangle grown by `margin`, as [[north, east], ...]."""
    h = math.radians(t.heading_deg)
    u, v = np.array([math.cos(h), math.sin(h)]), np.array([-math.sin(h), math.cos(h)])
    a, b = t.length / 2 + margin, t.width / 2 + margin
    return np.array([np.array([t.north, t.east]) + s * a * u + r * b * v for s, r in ((1, 1), (1, -1), (-1, -1),
                                                                                      (-1, 1))])


def photo_indices(path: np.ndarray, points: np.ndarray) -> list[int]:
    """For each photo point in order, the index of the nearest path point at or after the previous one's (a path
    that crosses itself keeps each photograph at its own pass)."""
    out, j0 = [], 0
    for p in points:
        j = j0 + int(np.argmin(np.hypot(path[j0:, 0] - p[0], path[j0:, 1] - p[1]))) if j0 < len(path) else j0
        out.append(j)
        j0 = j
    return out


def informative_plan(lawn: PhotoSurvey, area: np.ndarray, info: InformationField, grid: ClearanceGrid,
                     budget: float, start: np.ndarray, heading_deg: float, altitude: float, fov: tuple[float, float],
                     radius: float, safe_distance: float, seed: int) -> PhotoSurvey | InformativeSurvey:
    """The RIG plan over the area from `start` (the area's corner nearest the vehicle, entered on the heading it
    arrives with), with the lawnmower's path length as its budget (capped by the element's time); the lawnmower
    itself when the RIG finds no way (start not clear)."""
    try:
        plan = informative_survey_path(area, info, budget=budget, altitude=altitude, depth=float(lawn.path[0, 2]),
                                       turning_radius=radius, start=start, start_heading_deg=heading_deg,
                                       fov_deg=fov, overlap=OVERLAP, gain=GAIN, coverage_floor=COVERAGE_FLOOR,
                                       enough=ENOUGH, clearance=grid, safety_distance=safe_distance, seed=seed)
    except ValueError:  # the start is not clear
        return lawn
    return plan if len(plan.path) > 1 else lawn


class PhotoSurveyRun:
    """Drives the photo survey for `ExploreAgent` (which delegates `step` to it)."""

    def __init__(self, context: AgentContext, targets: list[Target]) -> None:
        m, p = context.mission, context.element.explore
        assert p is not None
        stereo = m.sensors.stereo
        if stereo is None:
            raise ValueError("a photo survey (rrt-photo) needs `sensors.stereo`")
        if not targets:
            raise ValueError(f"no object to photograph ('{p.object}')")
        self.context = context
        self.fov = (math.degrees(2 * math.atan(stereo.width / 2 / stereo.fx)),
                    math.degrees(2 * math.atan(stereo.height / 2 / stereo.fx)))
        self.altitude = min(p.safe_distance + NAV_MARGIN_M, 0.9 * stereo.max_range)
        self.payload: frozenset[str] = frozenset()
        self.photographs = "photograph" in context.element.actions  # without it the plan is flown, no photo taken
        self.finished = False
        self.plans: list[tuple[Target, PhotoSurvey | InformativeSurvey, np.ndarray]] = []
        self.fields: list[InformationField] = []
        here = np.array([context.nav.north, context.nav.east])
        for t in targets:
            area = target_area(t, MARGIN_M)
            products = survey_map_for(context.knowledge, t)
            info = InformationField(np.asarray(products["info"], dtype=float), float(products["north0"]),
                                    float(products["east0"]), float(products["cell"])) \
                if products is not None and "info" in products else InformationField(np.zeros((1, 1)), t.north,
                                                                                      t.east, 1.0)
            depth = t.top_depth - self.altitude
            lo = np.array([t.north - 20.0, t.east - 20.0, depth - 8.0])
            hi = np.array([t.north + 20.0, t.east + 20.0, t.bottom_depth + 1.0])
            grid = ClearanceGrid.from_voxel_map(prior_map(products, lo, hi, 0.5), lo, hi, unknown="free")
            lawn = photo_survey_path(area, info, altitude=self.altitude, depth=depth, fov_deg=self.fov,
                                     overlap=OVERLAP, gain=GAIN, turning_radius=m.vehicle.turn_radius,
                                     clearance=grid, safety_distance=p.safe_distance, seed=m.seed)
            budget = min(lawn.length, p.budget * SURVEY_SPEED * BUDGET_SHARE / len(targets))
            self.fields.append(info)
            start = area[int(np.argmin(np.hypot(area[:, 0] - here[0], area[:, 1] - here[1])))]
            heading = math.degrees(math.atan2(start[1] - here[1], start[0] - here[0]))
            plan = informative_plan(lawn, area, info, grid, budget, start, heading, self.altitude, self.fov,
                                    max(m.vehicle.turn_radius, MIN_RADIUS_M), p.safe_distance, m.seed)
            self.plans.append((t, plan, area))
            here = plan.path[-1, :2]
        self.index = 0
        self.phase = "approach"
        self.speed = m.vehicle.cruise_speed
        self.photos: list[dict[str, Any]] = []
        self.images: list[tuple[np.ndarray, np.ndarray]] = []
        self.cruise_depth = min(context.nav.depth, min(pl.path[:, 2].min() for _, pl, _ in self.plans))
        self._begin(context.nav.north, context.nav.east)

    def _begin(self, north: float, east: float) -> None:
        _, plan, _ = self.plans[self.index]
        self.follower = PathFollower((north, east), plan.path[:, :2], lookahead=4.0, acceptance=1.0)
        self.next_photo = 0
        self.photo_at = photo_indices(plan.path[:, :2], plan.photo_points[:, :2])

    def planned_path(self) -> list[tuple[float, float]]:
        return [(float(n), float(e)) for _, plan, _ in self.plans for n, e in plan.path[:, :2]]

    def step(self, observation: Observation) -> Command:
        nav = observation.nav
        target, plan, _ = self.plans[self.index]
        first = plan.path[0]
        if self.phase == "approach":
            distance = math.hypot(first[0] - nav.north, first[1] - nav.east)
            if distance > 2.0 * self.context.mission.vehicle.turn_radius:
                heading = math.degrees(math.atan2(first[1] - nav.east, first[0] - nav.north)) % 360.0
                return Command(heading, self.speed, depth=self.cruise_depth)
            self.phase = "survey"
        if self.payload and observation.stereo:  # a triggered pair has arrived
            frame = observation.stereo[-1]
            self.photos.append({"time": frame.time, "north": nav.north, "east": nav.east, "depth": nav.depth,
                                "heading": nav.heading, "target": target.id, "altitude_est": target.top_depth
                                - nav.depth})
            self.images.append((frame.left, frame.right))
            self.payload = frozenset()
            self.next_photo += 1
        points = plan.photo_points
        while not self.payload and self.next_photo < len(points) and \
                self.photo_at[self.next_photo] < self.follower.leg - 1 - SKIP_LEGS:
            self.next_photo += 1  # passed without coming near it: missed, the next one is due
        if self.photographs and not self.payload and self.next_photo < len(points):
            p = points[self.next_photo]
            ahead = (p[0] - nav.north) * math.cos(math.radians(nav.heading)) + \
                (p[1] - nav.east) * math.sin(math.radians(nav.heading))
            near = math.hypot(p[0] - nav.north, p[1] - nav.east)
            if near <= TRIGGER_M or (near <= 2.0 and ahead < 0.0):
                self.payload = frozenset({"stereo"})
        heading = self.follower.heading(nav.north, nav.east)
        if self.follower.done and not self.payload:
            self.index += 1
            if self.index >= len(self.plans):
                self.finished = True
                return Command.hold(nav)
            self.phase = "approach"
            self._begin(nav.north, nav.east)
        depth = float(plan.path[0, 2]) if self.phase == "survey" else self.cruise_depth
        return Command(heading, SURVEY_SPEED, depth=depth)

    def finish(self, report: ExploreReport) -> None:
        """Photo coverage per target and the products for the run folder."""
        objects: list[ExploredObject] = []
        for t, plan, _ in self.plans:
            taken = [p for p in self.photos if p["target"] == t.id]
            shapes = [footprint_polygon(p["north"], p["east"], p["heading"],
                                        2 * p["altitude_est"] * math.tan(math.radians(self.fov[0] / 2)),
                                        2 * p["altitude_est"] * math.tan(math.radians(self.fov[1] / 2)))
                      for p in taken]
            obj = Polygon([(e, n) for n, e in target_area(t, 0.0)])
            covered = shapely.union_all(shapes).intersection(obj).area / obj.area if shapes else 0.0
            objects.append(ExploredObject(t.id, t.source, round(t.north, 2), round(t.east, 2), {
                            "photos": len(taken), "planner": "rig" if isinstance(plan, InformativeSurvey)
                            else "lawnmower",
                            "planned_photos": int(len(plan.photo_points)), "altitude_m": round(self.altitude, 2),
                            "planned_length_m": round(plan.length, 1),
                            "photo_coverage_percent": round(100.0 * covered, 2)}))
        report.objects, report.views = objects, len(self.photos)
        report.figures["photo_coverage_percent"] = round(float(np.mean(
            [o.figures["photo_coverage_percent"] for o in objects])), 2) if objects else 0.0
        report.camera_fov_deg = [round(v, 2) for v in self.fov]
        report.photo_times = [round(p["time"], 3) for p in self.photos]
        index = np.array([[p["time"], p["north"], p["east"], p["depth"], p["heading"]] for p in self.photos],
                         dtype=float).reshape(-1, 5)
        products: dict[str, Any] = {
            "photo_index": index, "photo_path": np.concatenate([pl.path for _, pl, _ in self.plans]),
            "photo_points": np.concatenate([pl.photo_points for _, pl, _ in self.plans]),
            "photo_areas": np.stack([a for _, _, a in self.plans])}
        for k, field in enumerate(self.fields):  # the information map each target's plan was made over
            products[f"photo_info_{k}"] = np.asarray(field.values, dtype=float)
            products[f"photo_info_grid_{k}"] = np.array([field.north0, field.east0, field.cell])
        if self.images:
            products["photo_left"] = np.stack([left for left, _ in self.images])
            products["photo_right"] = np.stack([right for _, right in self.images])
        self.context.knowledge.maps[self.context.element.id] = products
