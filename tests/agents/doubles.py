"""Test doubles for the agents' plug-in calls: a host of scripted plug-ins whose results become ready `delay`
seconds of vehicle time after submission (answered in submission order per role, as the real host does), and
frames and estimates to feed them."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from mission.plugin_api import StereoImages
from mission.plugin_calls import PluginCall
from mission.vehicle import NavState


class ScriptedPlugin:
    """A perception plug-in that answers each frame with `answer(frame, request)`."""

    def __init__(self, answer: Callable[[StereoImages, Any], Any]):
        self.answer = answer
        self.requests: list[Any] = []

    def process(self, frame: StereoImages, request: Any) -> Any:
        self.requests.append(request)
        return self.answer(frame, request)


class ScriptedHost:
    """The host's contract (`has`, `submit` → `PluginCall`, `reset`, `close`) over scripted plug-ins."""

    def __init__(self, plugins: dict[str, ScriptedPlugin], delays: dict[str, float] | None = None):
        self.plugins = plugins
        self.delays = delays or {}

    def has(self, role: str) -> bool:
        return role in self.plugins

    def submit(self, role: str, frame: StereoImages, request: Any, now: float) -> PluginCall:
        result = self.plugins[role].process(frame, request)
        return PluginCall(role, frame.time, result, ready_at=now + self.delays.get(role, 0.0))

    def reset(self) -> None:
        return None

    def close(self) -> None:
        return None


def scripted_host(plugins: dict[str, ScriptedPlugin], delays: dict[str, float] | None = None) -> Any:
    """A host (delayed when `delays` is given) with scripted plug-ins by role."""
    return ScriptedHost(plugins, delays)


class LateCall:
    """A real call whose result is withheld until `delay` seconds of vehicle time after its submission."""

    def __init__(self, call: PluginCall, ready_at: float):
        self.call, self.ready_at, self.frame_time = call, ready_at, call.frame_time

    def poll(self, now: float) -> Any | None:
        return self.call.poll(now) if now >= self.ready_at else None


def frame_at(t: float) -> StereoImages:
    """A stereo frame at time `t` (its pixels do not matter to scripted plug-ins)."""
    blank = np.zeros((2, 2), dtype=np.uint8)
    return StereoImages(t, blank, blank, np.eye(3), 0.25)


def nav_at(t: float, north: float, east: float, depth: float, heading: float = 0.0,
           altitude: float | None = 4.0) -> NavState:
    return NavState(t, north, east, depth, heading, 0.0, altitude, 0.1, 100.0)
