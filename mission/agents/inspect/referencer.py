"""Referencing a placed or searched-for object (seed 002 §3.3, seed 000 approach 3): the request with its prior,
the gate that tells a wrong identification from a correction once odometry tracks the object, and the fusion of
several recognised views into one fix.

Calls are asynchronous (`PluginHost.submit`), one at a time: an `Attempt` keeps what the frame was taken with
(the navigation estimate and the object's placement then), and its result is judged with those."""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from mission.agents.fusion import Fused, View, fuse_views
from mission.agents.inspect.odometry import OdometryChain
from mission.agents.inspect.placement import Placement
from mission.agents.inspect.settings import InspectSettings
from mission.agents.known_object import attempt_record
from mission.geometry import invert, transform_points
from mission.plugin_api import PointSetModel, ReferencingRequest, ReferencingResult, StereoImages
from mission.plugin_calls import PluginCall
from mission.plugin_host import PluginHost
from mission.vehicle import NavState


@dataclass
class Attempt:
    """One referencing call under way: the frame, the estimate it was taken at, and what it was asked."""

    call: PluginCall
    frame: StereoImages
    nav: NavState
    T_world_cam: np.ndarray
    T_wo: np.ndarray  # the object's placement when the frame was taken
    searching: bool
    set_id: str
    passing: bool
    started: float  # perf_counter at submission


@dataclass
class Judged:
    """An attempt's result as the agent takes it: `recognised` after the ambiguity check and the gate."""

    attempt: Attempt
    result: ReferencingResult
    record: dict[str, Any]
    recognised: bool

    @property
    def T_world_object(self) -> np.ndarray:
        assert self.result.T_cam_object is not None
        return self.attempt.T_world_cam @ self.result.T_cam_object


class Referencer:
    """Submits referencing attempts, judges their results, and fuses the views of the set being referenced."""

    def __init__(self, plugins: PluginHost, object_id: str, sets: Mapping[str, np.ndarray], place: Placement,
                 chain: OdometryChain, settings: InspectSettings):
        self.plugins = plugins
        self.object_id = object_id
        self.sets = sets
        self.place = place
        self.chain = chain
        self.settings = settings
        self.pending: Attempt | None = None
        self.views: list[View] = []

    @property
    def busy(self) -> bool:
        return self.pending is not None

    def submit(self, frame: StereoImages, nav: NavState, set_id: str, ids: Sequence[str], searching: bool,
               passing: bool = False) -> None:
        """Ask the plug-in to recognise any of the sets `ids` in `frame` (taken at `nav`), with the prior of the
        object as placed now: database-wide while searching, centimetres once a set has been recognised."""
        s = self.settings
        T_world_cam = self.place.camera_in_world(nav)
        prior = invert(T_world_cam) @ self.place.T_wo
        radius = s.search_prior_radius_m if searching else s.fine_prior_radius_m
        models = tuple(PointSetModel(self.object_id, i, self.sets[i]) for i in ids)
        started = time.perf_counter()
        call = self.plugins.submit("referencing", frame, ReferencingRequest(models, prior, s.tolerance_m, radius),
                                   nav.time)
        self.pending = Attempt(call, frame, nav, T_world_cam, self.place.T_wo.copy(), searching, set_id, passing,
                               started)

    def poll(self, now: float) -> Judged | None:
        """The pending attempt's result, judged, once it is ready."""
        if self.pending is None:
            return None
        result: ReferencingResult | None = self.pending.call.poll(now)
        if result is None:
            return None
        attempt, self.pending = self.pending, None
        return self._judge(attempt, result)

    def _judge(self, attempt: Attempt, result: ReferencingResult) -> Judged:
        record: dict[str, Any] = {
            "time": attempt.frame.time, "stage": "search" if attempt.searching else "fine", "set": attempt.set_id,
            "recognised_set": result.set_id, **attempt_record(result),
            "time_ms": round(1e3 * (time.perf_counter() - attempt.started), 1)}
        if result.details.get("reason"):
            record["reason"] = result.details["reason"]
        # An ambiguous identification (the prior cannot choose between symmetric matches) is no fix.
        recognised = bool(result.recognised and result.T_cam_object is not None and not result.ambiguous)
        judged = Judged(attempt, result, record, recognised)
        if recognised and not attempt.searching and self.place.fixed and self.chain.enabled \
                and not self.chain.broken:
            self._gate(judged)
        if judged.recognised:
            record["T_object_cam"] = invert(judged.T_world_object) @ attempt.T_world_cam
        return judged

    def _gate(self, judged: Judged) -> None:
        """Re-referencing a tracked object, a view that moves the set farther from where odometry tracked it (at
        the frame's time) than the fix gate plus three times the assumed drift is a wrong identification."""
        points = self.sets[judged.attempt.set_id]
        jump = float(np.max(np.linalg.norm(transform_points(judged.T_world_object, points)
                                           - transform_points(judged.attempt.T_wo, points), axis=1)))
        s = self.settings
        gate = s.fix_gate_m + 3.0 * s.vo_drift_per_m * self.place.path_since_fix
        if jump > gate:
            judged.recognised = False
            judged.record["recognised"], judged.record["gated"] = False, True
            judged.record["reason"] = f"{jump:.2f} m from where odometry tracks the set (gate {gate:.2f} m)"

    def add_view(self, judged: Judged) -> None:
        """Keep a recognised view's points: in the object's tracked frame once it is placed (dead reckoning drifts
        centimetres over the minute the views take, so views that agree in the object's frame stopped agreeing
        in the navigation frame; measured: 6 good views, none fused), else in the navigation frame."""
        result = judged.result
        if result.model_points is None or result.points_cam is None:
            return
        T_world_cam = judged.attempt.T_world_cam
        frame_T = invert(judged.attempt.T_wo) @ T_world_cam if self.place.fixed else T_world_cam
        self.views.append((result.model_points, transform_points(frame_T, result.points_cam)))

    def fuse(self, agreement: float) -> Fused | None:
        """T_world_object from the agreeing views (composed with the tracked placement once the object is
        placed), or None while fewer than two agree."""
        fused = fuse_views(self.views, agreement) if len(self.views) >= 2 else None
        if fused is not None and self.place.fixed:  # the fusion corrects the tracked frame: compose it
            fused = fused._replace(T=self.place.T_wo @ fused.T)
        return fused
