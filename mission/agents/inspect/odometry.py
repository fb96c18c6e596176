"""The inspect agent's odometry chain (seed 003 on top of a seed 002 §3.4 fix): from a referenced frame on, the
odometry plug-in's motion composed with the fix gives the camera's pose in the object frame, and the object is
re-anchored in the (dead-reckoned) navigation frame on every frame, so the vehicle moves in the object's frame.

Calls are asynchronous (`PluginHost.submit`): a result is applied with the navigation estimate of its own frame,
results of a chain that a newer fix replaced are dropped, and until a result arrives nothing moves."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

import numpy as np

from mission.agents.inspect.placement import Placement
from mission.agents.inspect.settings import InspectSettings
from mission.agents.report import OdometryReport
from mission.plugin_api import OdometryRequest, OdometryResult, StereoImages
from mission.plugin_calls import PluginCall
from mission.plugin_host import PluginHost
from mission.vehicle import NavState


@dataclass
class OdometryStats:
    """Frames the plug-in answered, frames it lost, chains started, re-referencings the assumed drift asked for."""

    frames: int = 0
    lost: int = 0
    chains: int = 0
    rereferences: int = 0


@dataclass
class _Pending:
    call: PluginCall
    nav: NavState  # the estimate when the frame was taken: the result is applied with it
    chain: int
    origin: bool = False


@dataclass
class OdometryChain:
    """The chain since the last referenced frame: its origin (T_object_cam then), the path since, and the frames
    lost in a row. `report` gets [time, x, y, z] of the camera in the object frame per tracked frame, and the
    `stats` as of the last tracked frame."""

    plugins: PluginHost | None
    place: Placement
    settings: InspectSettings
    T_object_origin: np.ndarray | None = None
    path_m: float = 0.0
    lost: int = 0
    last_c: np.ndarray | None = None
    disagrees: bool = False  # odometry moved the object further than navigation can drift (see `_apply`)
    stats: OdometryStats = field(default_factory=OdometryStats)
    report: OdometryReport = field(default_factory=OdometryReport)
    _chain: int = 0
    _pending: deque[_Pending] = field(default_factory=deque)

    @property
    def enabled(self) -> bool:
        """Whether an odometry plug-in is loaded."""
        return self.plugins is not None and self.plugins.has("odometry")

    @property
    def active(self) -> bool:
        return self.T_object_origin is not None

    @property
    def broken(self) -> bool:
        return self.lost >= self.settings.vo_lost_frames or self.disagrees

    def assumed_drift_m(self) -> float:
        return self.settings.vo_drift_per_m * self.path_m

    def needs_rereference(self) -> bool:
        """Whether odometry is not to be trusted for the next target: no chain, tracking lost, or too much
        assumed drift."""
        if not self.enabled:
            return False
        return not self.active or self.broken or self.assumed_drift_m() > self.settings.rereference_drift_m

    def restart_budget(self) -> None:
        """Count the drift and lost frames afresh (the next re-referencing is due after as much motion again)."""
        self.path_m, self.lost, self.disagrees = 0.0, 0, False

    def start(self, frame: StereoImages, nav: NavState) -> None:
        """`frame` (taken at `nav`) is referenced: it becomes the origin of a new chain."""
        self.T_object_origin = self.place.camera_in_object(nav)
        self.path_m, self.lost, self.disagrees = 0.0, 0, False
        self.last_c = self.T_object_origin[:3, 3].copy()
        self._chain += 1
        if self.enabled:
            self._submit(frame, nav, OdometryRequest(set_origin=True, altitude=nav.altitude, speed=nav.speed), True)
            self.stats.chains += 1

    def feed(self, frame: StereoImages, nav: NavState) -> None:
        """Track `frame` (taken at `nav`) on the current chain."""
        if self.enabled and self.active:
            self._submit(frame, nav, OdometryRequest(altitude=nav.altitude, speed=nav.speed), False)

    def _submit(self, frame: StereoImages, nav: NavState, request: OdometryRequest, origin: bool) -> None:
        assert self.plugins is not None
        self._pending.append(_Pending(self.plugins.submit("odometry", frame, request, nav.time), nav, self._chain,
                                      origin))
        self.poll(nav.time)

    def poll(self, now: float) -> None:
        """Apply the results that are ready, in the order the frames were submitted."""
        while self._pending:
            result = self._pending[0].call.poll(now)
            if result is None:
                return
            pending = self._pending.popleft()
            if pending.origin or pending.chain != self._chain:
                continue
            self._apply(result, pending)

    def _apply(self, result: OdometryResult, pending: _Pending) -> None:
        """Move the object in the navigation frame so that the camera sits where odometry says it was."""
        assert self.T_object_origin is not None
        self.stats.frames += 1
        if not result.ok or result.T_origin_cam is None:
            self._lost_frame()
            return
        c = (self.T_object_origin @ result.T_origin_cam)[:3, 3]
        step = float(np.linalg.norm(c - self.last_c)) if self.last_c is not None else 0.0
        if step > self.settings.vo_max_step_m:
            self._lost_frame()
            return
        T_world_cam = self.place.camera_in_world(pending.nav)
        anchored = T_world_cam[:3, 3] - self.place.T_wo[:3, :3] @ c
        s = self.settings
        allowed = s.vo_object_shift_m + s.vo_object_shift_per_m * (self.place.path_since_fix + step)
        if float(np.linalg.norm(anchored - self.place.trusted[:3, 3])) > allowed:
            # Odometry and navigation disagree about how the vehicle moved by more than navigation can drift:
            # following odometry would drag the object (and the viewpoint the vehicle chases) along. End the
            # chain; the agent re-references.
            self.disagrees = True
            self._lost_frame()
            return
        self.lost = 0
        self.path_m += step
        self.place.path_since_fix += step
        self.last_c = c.copy()
        self.place.T_wo[:3, 3] = anchored
        self.report.track.append([round(pending.call.frame_time, 3), *(round(float(x), 4) for x in c)])
        stats = self.stats
        self.report.frames, self.report.lost = stats.frames, stats.lost
        self.report.chains, self.report.rereferences = stats.chains, stats.rereferences

    def _lost_frame(self) -> None:
        self.lost += 1
        self.stats.lost += 1
