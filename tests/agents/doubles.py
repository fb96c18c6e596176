"""Test doubles for the agents' plug-in calls: a scripted plug-in inside the real `PluginHost`, and a host whose
results become ready `delay` seconds of vehicle time after the frame was submitted (as an onboard host's do)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from mission.plugin_api import StereoImages
from mission.plugin_host import PluginCall, PluginHost
from mission.vehicle import NavState


class ScriptedPlugin:
    """A perception plug-in that answers each frame with `answer(frame, request)`."""

    def __init__(self, answer: Callable[[StereoImages, Any], Any]):
        self.answer = answer
        self.requests: list[Any] = []

    def configure(self, settings: Any) -> None:
        return None

    def process(self, frame: StereoImages, request: Any) -> Any:
        self.requests.append(request)
        return self.answer(frame, request)

    def reset(self) -> None:
        return None

    def close(self) -> None:
        return None


class DelayedHost(PluginHost):
    """The real host whose results become ready `delays[role]` seconds after submission (in submission order)."""

    def __init__(self, *args: Any, delays: dict[str, float] | None = None, **kwargs: Any):
        super().__init__(*args, **kwargs)
        self.delays = delays or {}

    def submit(self, role: str, frame: StereoImages, request: Any, now: float) -> PluginCall:
        result = self.process(role, frame, request, now)
        return PluginCall(role, frame.time, result, ready_at=now + self.delays.get(role, 0.0))


def scripted_host(plugins: dict[str, ScriptedPlugin], delays: dict[str, float] | None = None) -> PluginHost:
    """A host (delayed when `delays` is given) with scripted plug-ins by role."""
    host = DelayedHost({}, {}, lambda *a, **k: None, delays=delays)
    for role, plugin in plugins.items():
        host.plugins[role] = plugin
        host.names[role] = f"scripted-{role}"
    return host


def frame_at(t: float) -> StereoImages:
    """A stereo frame at time `t` (its pixels do not matter to scripted plug-ins)."""
    blank = np.zeros((2, 2), dtype=np.uint8)
    return StereoImages(t, blank, blank, np.eye(3), 0.25)


def nav_at(t: float, north: float, east: float, depth: float, heading: float = 0.0,
           altitude: float | None = 4.0) -> NavState:
    return NavState(t, north, east, depth, heading, 0.0, altitude, 0.1, 100.0)
