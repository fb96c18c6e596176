"""The executive's side of perception plug-ins: load them by name, configure them once, and contain their
faults. An exception or a call over the time budget becomes a `plugin_fault` event and a "not recognised"
result; the mission goes on per its policy.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from typing import Any

from mission.errors import PluginError
from mission.plugin_api import OdometryResult, PerceptionPlugin, ReferencingResult, StereoImages
from mission.plugins import load_plugin

DEFAULT_BUDGET_S = 5.0  # per call; generous for a software renderer's machine, tight enough to catch a hang


class PluginHost:
    """Plug-in instances by role (`referencing`, `odometry`), each call timed and guarded."""

    def __init__(self, roles: Mapping[str, str | None], settings: Mapping[str, Any], emit: Callable[..., None],
                 budget_s: float = DEFAULT_BUDGET_S, clock: Callable[[], float] = time.perf_counter):
        """`clock` times each call against `budget_s`: wall time onboard; the simulator passes the calling
        thread's CPU time (`time.thread_time`), the simulated onboard computer's, so that a loaded machine
        does not turn a normal call into a fault and change the run."""
        self.emit = emit
        self.budget_s = budget_s
        self.clock = clock
        self.plugins: dict[str, PerceptionPlugin] = {}
        self.names: dict[str, str] = {}
        for role, name in roles.items():
            if name is None:
                continue
            factory = load_plugin(name)
            try:
                instance = factory()
                instance.configure(settings)
            except Exception as exc:
                raise PluginError(f"perception plug-in '{name}' ({role}) failed to start: {exc!r}") from exc
            if not isinstance(instance, PerceptionPlugin):
                raise PluginError(f"perception plug-in '{name}' does not implement configure/process/reset/close")
            self.plugins[role] = instance
            self.names[role] = name
        self.calls: list[dict[str, Any]] = []

    def has(self, role: str) -> bool:
        return role in self.plugins

    def process(self, role: str, frame: StereoImages, request: Any, now: float) -> Any:
        """Call a plug-in; on a fault or an overrun, log it and return a "not recognised" result."""
        plugin = self.plugins.get(role)
        if plugin is None:
            return _failed(role, f"no '{role}' plug-in configured")
        t0 = self.clock()
        try:
            result = plugin.process(frame, request)
        except Exception as exc:
            elapsed = self.clock() - t0
            self.emit("plugin_fault", now, plugin=self.names[role], role=role, error=repr(exc),
                      elapsed_ms=1e3 * elapsed)
            return _failed(role, f"plug-in fault: {exc!r}", elapsed_ms=1e3 * elapsed)
        elapsed = self.clock() - t0
        if elapsed > self.budget_s:
            self.emit("plugin_fault", now, plugin=self.names[role], role=role,
                      error=f"over its time budget ({1e3 * elapsed:.0f} ms > {1e3 * self.budget_s:.0f} ms)",
                      elapsed_ms=1e3 * elapsed)
            return _failed(role, "over the time budget", elapsed_ms=1e3 * elapsed)
        return result

    def submit(self, role: str, frame: StereoImages, request: Any, now: float) -> PluginCall:
        """Hand a frame to a plug-in without waiting for it; `PluginCall.poll(now)` gives the result once it is
        ready (tagged with `frame.time`: the agent uses it at that time, with the navigation estimate then).

        A fault or an overrun gives the role's "no answer" result, as `process` does."""
        return PluginCall(role, frame.time, self.process(role, frame, request, now), ready_at=now)

    def reset(self) -> None:
        for role, plugin in self.plugins.items():
            try:
                plugin.reset()
            except Exception as exc:
                self.emit("plugin_fault", 0.0, plugin=self.names[role], role=role, error=repr(exc))

    def close(self) -> None:
        for role, plugin in self.plugins.items():
            try:
                plugin.close()
            except Exception as exc:
                self.emit("plugin_fault", 0.0, plugin=self.names[role], role=role, error=repr(exc))


class PluginCall:
    """A plug-in call under way. `poll(now)` is None until the result is ready at the vehicle's time `now`."""

    def __init__(self, role: str, frame_time: float, result: Any = None, ready_at: float = float("inf")):
        self.role = role
        self.frame_time = frame_time
        self._result = result
        self._ready_at = ready_at

    def poll(self, now: float) -> Any | None:
        return self._result if now >= self._ready_at else None


def _failed(role: str, reason: str, **details: Any) -> ReferencingResult | OdometryResult:
    """The "no answer" result of a role: lost tracking for odometry, "not recognised" otherwise."""
    if role == "odometry":
        return OdometryResult.lost(reason, **details)
    return ReferencingResult.not_recognised(reason, **details)
