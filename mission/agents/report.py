"""What agents hand to the metrics when their element ends: one dataclass per agent kind, read by attribute.

`as_json()` gives the element's own fields of `metrics.json` (the output contract). Referencing attempts stay
JSON records: they are logged as they happen (`referencing_attempt` events) and a multi-view plug-in adds its own
fields to them (`approach`, `elements`, `table`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from mission.knowledge import DetectedObject


@dataclass
class AgentReport:
    """An element whose agent reports nothing beyond its status (transit, hover)."""

    def as_json(self) -> dict[str, Any]:
        return {}


@dataclass
class ReferenceReport(AgentReport):
    """A `reference` element: every attempt, and which one is the fused result (`final`, an index)."""

    object: str
    attempts: list[dict[str, Any]] = field(default_factory=list)
    final: int | None = None

    def as_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"object": self.object, "attempts": self.attempts}
        if self.final is not None:
            out["final"] = self.final
        return out


@dataclass
class TargetOutcome:
    """One target of an inspection: the photos asked for and taken, and the viewpoint (object frame): the planned
    one, which rule planned it (`designed`, `raised`, `oblique`: `mission.agents.inspect.viewpoint`) and the
    designed one."""

    photos_requested: int
    reference: str
    photos: int = 0
    viewpoint_object: list[float] | None = None
    designed_object: list[float] | None = None
    viewpoint: str = "designed"

    @property
    def done(self) -> bool:
        return self.photos >= self.photos_requested

    def as_json(self) -> dict[str, Any]:
        return {"photos_requested": self.photos_requested, "photos": self.photos,
                "viewpoint_object": self.viewpoint_object, "reference": self.reference,
                "designed_object": self.designed_object, "viewpoint": self.viewpoint}


@dataclass
class Photo:
    """A photograph as taken: where the agent believed the camera was (`T_object_cam_est`), the planned viewpoint
    it aimed at and the designed one (`designed_object`; `viewpoint`: the rule that planned it), all in the
    object frame."""

    target: str
    index: int
    time: float
    file: str
    viewpoint_object: list[float]
    T_object_cam_est: list[list[float]]
    camera_error_est_m: float
    altitude_limited: bool
    odometry_path_m: float
    designed_object: list[float] | None = None
    viewpoint: str = "designed"

    def as_json(self) -> dict[str, Any]:
        return {"target": self.target, "index": self.index, "time": self.time, "file": self.file,
                "viewpoint_object": self.viewpoint_object, "T_object_cam_est": self.T_object_cam_est,
                "camera_error_est_m": self.camera_error_est_m, "altitude_limited": self.altitude_limited,
                "odometry_path_m": self.odometry_path_m, "designed_object": self.designed_object,
                "viewpoint": self.viewpoint}


@dataclass
class OdometryReport:
    """The odometry chains of an inspection: the camera's tracked positions in the object frame ([time, x, y, z])
    and the counts as of the last tracked frame."""

    track: list[list[float]] = field(default_factory=list)
    frames: int = 0
    lost: int = 0
    chains: int = 0
    rereferences: int = 0

    def counts(self) -> dict[str, int]:
        return {"frames": self.frames, "lost": self.lost, "chains": self.chains, "rereferences": self.rereferences}


@dataclass
class InspectReport(AgentReport):
    """An `inspect` element: the order (as planned, then each re-plan after a `["replan", set]` marker), the
    attempts, photos and re-plans, the odometry, and each target's outcome."""

    object: str
    order: list[list[Any]]
    plan_length_m: float
    exact_order: bool
    targets: dict[str, TargetOutcome]
    attempts: list[dict[str, Any]] = field(default_factory=list)
    photos: list[Photo] = field(default_factory=list)
    replans: list[dict[str, Any]] = field(default_factory=list)
    vo: OdometryReport = field(default_factory=OdometryReport)
    unreachable: list[Any] = field(default_factory=list)

    def as_json(self) -> dict[str, Any]:
        return {"object": self.object, "order": self.order, "plan_length_m": self.plan_length_m,
                "exact_order": self.exact_order, "attempts": self.attempts,
                "photos": [p.as_json() for p in self.photos], "replans": self.replans,
                "vo": {"track": self.vo.track, **self.vo.counts()},
                "targets": {tid: t.as_json() for tid, t in self.targets.items()}, "unreachable": self.unreachable}


@dataclass
class SurveyReport(AgentReport):
    """A `survey` element: its meander plan and, once it has ended, its coverage, pings and detections (each
    with the database object it was matched to, if any)."""

    spacing_m: float
    heading_deg: float
    planned_length_m: float
    turns: int
    cells: int
    coverage_percent: float | None = None
    pings: int | None = None
    detections: list[DetectedObject] | None = None

    def as_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"spacing_m": self.spacing_m, "heading_deg": self.heading_deg,
                               "planned_length_m": self.planned_length_m, "turns": self.turns, "cells": self.cells}
        if self.detections is not None:
            out.update({"coverage_percent": self.coverage_percent, "pings": self.pings,
                        "detections": [_detection(d) for d in self.detections]})
        return out


def _detection(d: DetectedObject) -> dict[str, Any]:
    return {"id": d.id, "north": round(d.north, 2), "east": round(d.east, 2), "length": round(d.length, 2),
            "width": round(d.width, 2), "height": round(d.height, 2), "heading_deg": round(d.heading_deg, 1),
            "matched_id": d.database_id}


@dataclass
class ExploredObject:
    """One object an `explore` element worked on: `source` says where the agent learnt of it ("database" or
    the survey's detection), `north`/`east` where it was believed to be; `figures` are the planner's own
    (views, coverage estimate, timings for next-best-view; photos, passes, coverage for a photo survey)."""

    id: str
    source: str
    north: float
    east: float
    figures: dict[str, Any] = field(default_factory=dict)

    def as_json(self) -> dict[str, Any]:
        return {"id": self.id, "source": self.source, "north": self.north, "east": self.east, **self.figures}


@dataclass
class ExploreReport(AgentReport):
    """An `explore` element: the planner, the objects and the views taken; `resolution_m` for next-best-view
    (the map's voxel size), `camera_fov_deg` and `photo_times` for a photo survey; `figures` the rest of the
    element's own figures (timings, distances, coverage)."""

    planner: str
    objects: list[ExploredObject] = field(default_factory=list)
    views: int = 0
    resolution_m: float | None = None
    camera_fov_deg: list[float] | None = None
    photo_times: list[float] | None = None
    figures: dict[str, Any] = field(default_factory=dict)

    def as_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"planner": self.planner, "objects": [o.as_json() for o in self.objects],
                               "views": self.views}
        if self.resolution_m is not None:
            out["resolution_m"] = self.resolution_m
        if self.camera_fov_deg is not None:
            out["camera_fov_deg"] = self.camera_fov_deg
        if self.photo_times is not None:
            out["photo_times"] = self.photo_times
        out.update(self.figures)
        return out
