"""The `survey` agent (seed 002 §2.1): fly a meander over the area at a constant altitude with the multibeam on,
fuse every ping into a voxel occupancy map at the estimated pose, then build the height and information maps and
detect objects as anomalies, matching them to the onboard database (unknown ones feed `explore: detected`).

Flying at a constant altitude keeps the swath constant over the terrain, so line spacing follows from the
altitude, the aperture and the overlap alone.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import shapely
from shapely.geometry import Polygon

from mission.agents.base import Agent, AgentContext
from mission.agents.report import SurveyReport
from mission.agents.waypoints import PathFollower
from mission.knowledge import DetectedObject, Knowledge
from mission.language.models import KnownObject, Survey
from mission.vehicle import Command, Observation, SonarPing
from planners.bathymetry import SoundingGrid
from planners.coverage import line_spacing, meander
from planners.detection import Detection, detect_anomalies
from planners.infomap import information_map
from planners.occupancy import VoxelMap

MAP_MARGIN_M = 10.0
GRID_CELL_M = 0.5  # bathymetric grid cell; finer than the sounding spacing at the swath edge leaves holes
MIN_OBJECT_HEIGHT_M = 0.8  # objects of 1 m and more are sought; the margin absorbs sounding and grid noise
MATCH_MARGIN_M = 5.0  # how far off its charted pose a database object may be found and still be "known"


def ping_endpoints(ping: SonarPing) -> tuple[np.ndarray, np.ndarray]:
    """Origin and beam endpoints (NED) of a ping placed at its estimated pose (flat vehicle attitude)."""
    a = np.radians(ping.angles_deg)
    h = math.radians(ping.heading)
    starboard = ping.ranges * np.sin(a)
    down = ping.ranges * np.cos(a)
    origin = np.array([ping.north, ping.east, ping.depth])
    ends = np.column_stack([origin[0] - starboard * math.sin(h), origin[1] + starboard * math.cos(h),
                            origin[2] + down])
    return origin, ends


def charted_centre(obj: KnownObject) -> tuple[float, float]:
    """Centre of a database object's footprint (its frame's origin is a corner, x along the heading)."""
    h = math.radians(obj.pose.heading)
    dx, dy = obj.size[0] / 2, obj.size[1] / 2
    return (obj.pose.north + dx * math.cos(h) - dy * math.sin(h), obj.pose.east + dx * math.sin(h) + dy * math.cos(h))


def match_database(found: Detection, database: list[KnownObject]) -> str | None:
    """The database object a detection is, if one is charted close enough (its size plus a margin)."""
    best, best_d = None, math.inf
    for obj in database:
        cn, ce = charted_centre(obj)
        d = math.hypot(found.north - cn, found.east - ce)
        if d <= 0.5 * math.hypot(obj.size[0], obj.size[1]) + MATCH_MARGIN_M and d < best_d:
            best, best_d = obj.id, d
    return best


class SurveyAgent(Agent):
    kind = "survey"

    def start(self, context: AgentContext) -> None:
        p = context.element.survey
        mbes = context.mission.sensors.mbes
        assert p is not None and mbes is not None
        m, nav = context.mission, context.nav
        self.params, self.context = p, context
        self.payload = frozenset({"mbes"})
        self.spacing = line_spacing(p.altitude, mbes.swath_deg, p.overlap)
        self.plan = meander(p.area, p.exclude, spacing=self.spacing, heading=p.heading,
                            turn_radius=m.vehicle.turn_radius, start=(nav.north, nav.east))
        self.follower = PathFollower((nav.north, nav.east), self.plan.waypoints,
                                     lookahead=max(2.0 * m.vehicle.turn_radius, 8.0),
                                     acceptance=max(0.5 * m.vehicle.turn_radius, 2.0))
        self.speed = p.speed or m.vehicle.cruise_speed
        self.map = VoxelMap(p.resolution)
        e_lo, n_lo, e_hi, n_hi = Polygon([(e, n) for n, e in p.area]).bounds
        self.grid = SoundingGrid((n_lo - MAP_MARGIN_M, n_hi + MAP_MARGIN_M), (e_lo - MAP_MARGIN_M, e_hi + MAP_MARGIN_M),
                                 cell=max(p.resolution, GRID_CELL_M))
        self.pings = 0
        self.sigmas: list[float] = []
        self.details = self.report = SurveyReport(round(self.spacing, 2), round(self.plan.heading_deg, 1),
                                                  round(self.plan.length_m, 1), self.plan.turns, self.plan.cells)

    def planned_path(self) -> list[tuple[float, float]]:
        return self.follower.points

    def step(self, observation: Observation) -> Command:
        for ping in observation.sonar:
            origin, ends = ping_endpoints(ping)
            self.map.insert_scan(origin, ends, ping.hit)
            self.grid.add(ends[ping.hit])
            self.pings += 1
            self.sigmas.append(ping.position_sigma)
        nav = observation.nav
        heading = self.follower.heading(nav.north, nav.east)
        if self.follower.done:
            self.succeed()
        return Command(heading, self.speed, altitude=self.params.altitude)

    def stop(self) -> None:
        """Turn the map into products: height and information maps, coverage, detections."""
        if not hasattr(self, "map"):
            return
        detect = "detect_objects" in self.context.element.actions
        products = survey_products(self.grid, self.params, float(np.mean(self.sigmas)) if self.sigmas else 1.0,
                                   detect)
        products["voxels_occupied"] = len(self.map.occupied_keys())
        products["voxel_memory_mb"] = round(self.map.memory_bytes / 1e6, 1)
        knowledge: Knowledge = self.context.knowledge
        element = self.context.element.id
        database = self.context.mission.objects
        detections: list[DetectedObject] = []
        for k, d in enumerate(products.pop("detections")):
            db_id = match_database(d, database)
            obj = DetectedObject(id=db_id or f"{element}-{k + 1}", north=d.north, east=d.east, length=d.length,
                                 width=d.width, height=d.height, heading_deg=d.heading_deg, depth=d.top_depth,
                                 database_id=db_id, element=element)
            knowledge.detections.append(obj)
            detections.append(obj)
        knowledge.maps[element] = {**products, "lines": [line.tolist() for line in self.plan.lines]}
        self.report.coverage_percent = round(products["coverage_percent"], 2)
        self.report.pings, self.report.detections = self.pings, detections


def survey_products(grid: SoundingGrid, p: Survey, nav_sigma: float, detect: bool = True) -> dict[str, Any]:
    """Height map (the gridded soundings), information map, coverage of the free area and detections."""
    area = Polygon([(e, n) for n, e in p.area])
    free = area.difference(shapely.union_all([Polygon([(e, n) for n, e in z]) for z in p.exclude])) \
        if p.exclude else area
    depth = grid.depth()
    cell = grid.cell
    rows, cols = depth.shape
    nn, ee = np.meshgrid(grid.north0 + cell * np.arange(rows), grid.east0 + cell * np.arange(cols), indexing="ij")
    inside = shapely.contains_xy(free, ee, nn)
    coverage = 100.0 * float((np.isfinite(depth) & inside).sum()) / max(int(inside.sum()), 1)
    info = information_map(depth, cell, nav_sigma)
    found = detect_anomalies(depth, grid.north0, grid.east0, cell, info, min_height=MIN_OBJECT_HEIGHT_M) \
        if detect else []
    found = [d for d in found if shapely.contains_xy(free, d.east, d.north)]
    return {"depth": depth, "info": info, "north0": grid.north0, "east0": grid.east0, "cell": cell,
            "coverage_percent": coverage, "nav_sigma_m": nav_sigma, "detections": found}
