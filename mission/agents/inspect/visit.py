"""Referencing at a point set (seed 002 §3.4, seed 000 approach 3): until the object is first placed, search for
any of its sets over the search pattern (frames on the way count too), then take fine views over the set that
was recognised and fuse them into a fix; a placed object goes straight to the fine views. The stages and phases
are in `mission.agents.inspect.states`."""

from __future__ import annotations

import math
from collections.abc import Collection, Mapping
from typing import Any, Protocol

import numpy as np

from mission.agents.base import Agent, AgentContext
from mission.agents.fusion import Fused
from mission.agents.hover import Goal
from mission.agents.inspect.motion import Mover
from mission.agents.inspect.odometry import OdometryChain
from mission.agents.inspect.placement import Placement
from mission.agents.inspect.referencer import Judged, Referencer
from mission.agents.inspect.settings import InspectSettings
from mission.agents.inspect.states import Phase, Stage
from mission.agents.inspect.viewing import SetViewer
from mission.geometry import invert
from mission.language.models import Search
from mission.plugin_api import StereoImages
from mission.vehicle import Command, NavState

STEREO = frozenset({"stereo"})


class SetStops(Protocol):
    """What a set visit tells the agent that sequences the stops (and asks it)."""

    def failed_sets(self) -> Collection[str]: ...

    def switched(self, planned: str) -> None: ...

    def referenced(self, set_id: str, nav: NavState) -> None: ...

    def set_failed(self, set_id: str, nav: NavState) -> None: ...

    def rereference_failed(self, nav: NavState) -> None: ...

    def search_failed(self, reason: str, nav: NavState) -> None: ...


class SetVisit:
    """The visit of one set at a time (`begin`, then `step` every tick); the search pattern and what it has
    ruled out persist across sets. `wants` is the agent whose sensor wishes (payload, frame rate, navigation
    aiding) the visit sets."""

    def __init__(self, context: AgentContext, object_id: str, sets: Mapping[str, np.ndarray], search: Search,
                 place: Placement, viewer: SetViewer, chain: OdometryChain, referencer: Referencer, mover: Mover,
                 stops: SetStops, wants: Agent, attempts: list[dict[str, Any]], settings: InspectSettings):
        self.context, self.object_id, self.sets, self.search = context, object_id, sets, search
        self.place, self.viewer, self.chain, self.referencer, self.mover = place, viewer, chain, referencer, mover
        self.stops, self.wants, self.attempts, self.settings = stops, wants, attempts, settings
        self.set_id = ""
        self.revisit = False  # the set was referenced before (the object is tracked): failing it costs nothing
        self.stage = Stage.SEARCH
        self.phase = Phase.GO
        self.goals: list[Goal] = []
        self.goal_index = 0
        self.search_goals: list[Goal] = []
        self.search_index = 0
        self.search_started: float | None = None
        self.unconfirmed: set[str] = set()  # sets whose search hit the closer views did not confirm
        self.fine_tries = 0
        self.hold_since = math.nan

    # -- stages ------------------------------------------------------------------------------------------------
    def begin(self, set_id: str, revisit: bool) -> None:
        self.set_id, self.revisit = set_id, revisit
        self.referencer.views = []
        self.fine_tries = 0
        if self.place.fixed:  # a good estimate already: straight to the precise referencing
            self._begin_fine(set_id)
            return
        # Until the object is first referenced, the vehicle searches for any of its sets: over each set as the
        # database places it, then the search pattern around it; one budget for the search.
        self.stage = Stage.SEARCH
        if not self.search_goals:
            self.search_goals[:] = self.viewer.search_goals(self.place, self.search.pattern)
        self.goals, self.goal_index = self.search_goals, self.search_index
        self.phase = Phase.GO

    def _begin_fine(self, set_id: str) -> None:
        self.set_id, self.stage = set_id, Stage.FINE
        self.referencer.views, self.fine_tries = [], 0
        self._next_fine_view()

    def _next_fine_view(self) -> None:
        k = len(self.referencer.views) + self.fine_tries
        self.goals, self.goal_index, self.phase = [self.viewer.fine_goal(self.place, self.set_id, k)], 0, Phase.GO

    def _resume_search(self, nav: NavState) -> None:
        self.stage, self.goals, self.referencer.views, self.fine_tries = Stage.SEARCH, self.search_goals, [], 0
        self.search_index += 1
        self.goal_index, self.phase = self.search_index, Phase.GO
        if self.search_index >= len(self.search_goals):
            self._search_failed(nav, f"no set of '{self.object_id}' recognised at {len(self.goals)} search positions")

    def _search_failed(self, nav: NavState, reason: str) -> None:
        self.context.emit("object_not_found", nav.time, element=self.context.element.id, reason=reason)
        self.stops.search_failed(reason, nav)

    def _set_failed(self, nav: NavState, reason: str) -> None:
        if not self.place.fixed:  # what an unconfirmed search result suggested is dropped (a placed object is tracked)
            self.place.fall_back()
        self.context.emit("set_not_recognised", nav.time, element=self.context.element.id, set=self.set_id,
                          reason=reason, attempts=sum(1 for a in self.attempts if a["set"] == self.set_id))
        self.stops.set_failed(self.set_id, nav)

    def _rereference_failed(self, nav: NavState) -> None:
        """A set referenced here before was not recognised again, or its views did not agree: the set is still
        good and the object still tracked. Go on by odometry (its chain continues) rather than give the set up."""
        self.context.emit("rereference_failed", nav.time, element=self.context.element.id, set=self.set_id,
                          odometry_path_m=round(self.chain.path_m, 3))
        self.chain.restart_budget()  # the next attempt is due after as much motion again
        self.stops.rereference_failed(nav)

    def _failed_here(self, nav: NavState, reason: str) -> None:
        """The fine views gave no fix: what it costs depends on what was known before."""
        if self.place.fixed and self.revisit:
            self._rereference_failed(nav)
        elif self.place.fixed:
            self._set_failed(nav, reason)
        else:  # the search's hit was not confirmed: drop it
            self.place.fall_back()
            self._resume_search(nav)

    # -- results -----------------------------------------------------------------------------------------------
    def poll(self, nav: NavState) -> None:
        """Take the referencing result if it is ready (`nav`: the estimate now)."""
        judged = self.referencer.poll(nav.time)
        if judged is not None:
            self._handle(judged, nav)

    def _submit(self, frame: StereoImages, nav: NavState, passing: bool) -> None:
        # Searching, any set that is in view will do (the more sets, the surer the identification); once the
        # object is placed, the set the plan visits.
        failed = self.stops.failed_sets()
        ids = [s for s in self.sets if s not in failed and s not in self.unconfirmed] \
            if self.stage is Stage.SEARCH else [self.set_id]
        ids = ids or [s for s in self.sets if s not in failed] or list(self.sets)
        self.referencer.submit(frame, nav, self.set_id, ids, self.stage is Stage.SEARCH, passing)
        self.poll(nav)

    def _handle(self, judged: Judged, nav: NavState) -> None:
        record, attempt = judged.record, judged.attempt
        self.attempts.append(record)
        self.context.emit("referencing_attempt", nav.time, element=self.context.element.id,
                          **{k: v for k, v in record.items() if not k.startswith("T_") and k != "time"})
        if not judged.recognised:
            if not attempt.passing:
                self._not_recognised(judged, nav)
            return
        if not self.place.fixed:  # placing the object: each view refines the coarse prior the next one is taken with
            self.place.T_wo = judged.T_world_object
        # Re-referencing a placed object, odometry keeps tracking it: the views count only once they agree
        # (a single wrong view must move neither the object nor the odometry chain's origin).
        if self.stage is Stage.SEARCH:
            recognised = judged.result.set_id
            if recognised is not None and recognised != self.set_id:
                # Referenced through the set that is in view; the planned one keeps its turn, now with a prior.
                self.context.emit("set_switched", nav.time, element=self.context.element.id, planned=self.set_id,
                                  recognised=recognised)
                self.stops.switched(self.set_id)
                self.set_id = str(recognised)
            self.search_index = self.goal_index
            self._begin_fine(self.set_id)
            return
        self.referencer.add_view(judged)
        fused = self.referencer.fuse(self.viewer.agreement(self.set_id))
        fine_views = self.settings.fine_views
        agreeing = fused.views if fused is not None else 0
        if fused is not None:
            self.attempts.append({**{k: v for k, v in record.items() if not k.startswith("T_")},
                                  "stage": "fused", "views": fused.views, "matched": fused.points,
                                  "residual_m": fused.residual_m,
                                  "T_object_cam": invert(fused.T) @ attempt.T_world_cam})
            if not self.place.fixed or agreeing >= fine_views:
                self.place.T_wo = fused.T
        if not self.place.fixed or agreeing >= fine_views:
            self._start_chain(attempt.frame, attempt.nav)
        if agreeing < fine_views and len(self.referencer.views) >= 2 * fine_views:
            self._failed_here(nav, f"{len(self.referencer.views)} views of the set do not agree")
            return
        if fused is not None and agreeing >= fine_views:  # two agreeing views can both be wrong the same way
            self._referenced(nav, fused)
            return
        self._next_fine_view()

    def _referenced(self, nav: NavState, fused: Fused) -> None:
        """The fused views fix the object: trust it and go on."""
        self.place.fix(fused.T)
        self.context.emit("referenced", nav.time, element=self.context.element.id, set=self.set_id,
                          views=fused.views, points=fused.points, residual_m=round(fused.residual_m, 4))
        self.stops.referenced(self.set_id, nav)

    def _not_recognised(self, judged: Judged, nav: NavState) -> None:
        self.chain.feed(judged.attempt.frame, judged.attempt.nav)  # the frame still carries the odometry chain
        if self.stage is Stage.FINE:
            self.fine_tries += 1
            # a hit that a closer view has confirmed keeps the longer budget of a placed object
            budget = 3 * self.settings.fine_views if self.place.fixed or self.referencer.views \
                else self.settings.confirm_tries
            if self.fine_tries <= budget:
                self._next_fine_view()
            elif self.place.fixed:
                self._failed_here(nav, "not recognised from above the set")
            else:  # the search's hit was not confirmed: drop it, and trust no more search hits on this set
                self.place.fall_back()
                self.unconfirmed.add(self.set_id)
                self.context.emit("search_hit_dropped", nav.time, element=self.context.element.id, set=self.set_id)
                self._resume_search(nav)
            return
        self.goal_index += 1
        self.search_index = self.goal_index
        self.phase = Phase.GO
        if self.goal_index >= len(self.goals):
            self._search_failed(nav, f"no set of '{self.object_id}' recognised at {len(self.goals)} search positions")

    def _start_chain(self, frame: StereoImages, nav: NavState) -> None:
        """This frame is referenced: it becomes the origin of a new odometry chain."""
        self.chain.start(frame, nav)
        self.wants.frame_rate_hz = self.settings.frame_rate_hz
        self.wants.payload = STEREO
        self.wants.navigation = "dead-reckoning"

    # -- the loop ----------------------------------------------------------------------------------------------
    def step(self, nav: NavState, frame: StereoImages | None) -> Command:
        s = self.settings
        if not self.place.fixed and self.search_started is not None and \
                nav.time - self.search_started > self.search.budget:
            self._search_failed(nav, f"no set of '{self.object_id}' recognised within the search budget "
                                     f"({self.search.budget:.0f} s)")
            return Command.hold(nav)
        goal = self.goals[self.goal_index]
        if self.phase is Phase.CAPTURE and frame is not None and not self.referencer.busy:
            self.phase = Phase.AWAIT
            self._submit(frame, nav, passing=False)
            return Command(goal.heading, 0.0, depth=goal.depth, station=(goal.north, goal.east))
        if frame is not None and self.stage is Stage.SEARCH and self.phase is Phase.GO:
            # Searching, every frame on the way at about the search depth is a chance (seed 002 §3.4: the
            # search motions go on until a set is recognised).
            if self.search_started is not None and abs(nav.depth - goal.depth) <= s.passing_depth_m \
                    and not self.referencer.busy:
                self._submit(frame, nav, passing=True)
                if self.stage is not Stage.SEARCH:  # a hit: the fine views start from here
                    return Command.hold(nav)
        elif frame is not None and self.phase not in (Phase.CAPTURE, Phase.AWAIT):
            self.chain.feed(frame, nav)
        command, there = self.mover.go(nav, goal)
        if self.phase is Phase.GO and there:
            self.phase, self.hold_since = Phase.SETTLE, nav.time
            if self.stage is Stage.SEARCH and self.search_started is None:
                self.search_started = nav.time  # the budget counts from the first search position
                self.wants.navigation = "dead-reckoning"  # near the object, relative navigation is steadier
        elif self.phase is Phase.SETTLE and nav.time - self.hold_since >= s.settle_s:
            self.phase = Phase.CAPTURE
            self.wants.payload = STEREO
        if self.phase is Phase.GO and self.stage is Stage.SEARCH and self.search_started is not None:
            self.wants.payload, self.wants.frame_rate_hz = STEREO, s.passing_rate_hz
        elif self.phase is Phase.GO and not self.chain.active:
            self.wants.payload = frozenset()  # no chain to feed: frames only when capturing
        return command
