"""Perception plug-ins that misbehave on purpose, for tests of the plug-in host (`mission.plugin_host`).

Name them by import path, e.g. `PluginHost({"referencing": "mission.testing_plugins:SleepingPlugin"}, …)`. Each
answers an ordinary frame (any request but `FAULT`) with a `ReferencingResult` that echoes the frame (its time
and the mean of its left image) and counts the calls since `configure`; given the request `FAULT`, it does its
one fault: sleep 30 s, segfault, exit, raise, or return what cannot be sent back. `SlowPlugin` answers every
frame correctly after burning `settings["cpu_s"]` seconds of CPU time (default 0.2); `BrokenPlugin` fails to
configure; `StartsOncePlugin` configures once per marker file and segfaults on `FAULT` (its worker cannot restart).
"""

from __future__ import annotations

import ctypes
import os
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from mission.plugin_api import ReferencingResult, StereoImages

FAULT = "fault"  # the request that makes a misbehaving plug-in misbehave


class EchoPlugin:
    """Answers every frame with its time, its left image's mean and the calls since `configure`."""

    def configure(self, settings: Mapping[str, Any]) -> None:
        self.settings = dict(settings)
        self.calls = 0

    def process(self, frame: StereoImages, request: Any) -> ReferencingResult:
        self.calls += 1
        if request == FAULT:
            self.fault()
        return ReferencingResult(True, set_id="echo", matched=self.calls,
                                 details={"frame_time": frame.time, "left_mean": float(frame.left.mean()),
                                          "pid": os.getpid()})

    def fault(self) -> None:
        """What this plug-in does wrong (nothing, for the echo)."""

    def reset(self) -> None:
        self.calls = 0

    def close(self) -> None:
        return None


class SleepingPlugin(EchoPlugin):
    """Hangs for `settings["sleep_s"]` (default 30 s) on a `FAULT` request."""

    def fault(self) -> None:
        time.sleep(float(self.settings.get("sleep_s", 30.0)))


class SegfaultingPlugin(EchoPlugin):
    """Reads address 0 on a `FAULT` request: a real segmentation fault."""

    def fault(self) -> None:
        ctypes.string_at(0)


class ExitingPlugin(EchoPlugin):
    """Leaves the process with `os._exit(3)` on a `FAULT` request."""

    def fault(self) -> None:
        os._exit(3)


class RaisingPlugin(EchoPlugin):
    """Raises on a `FAULT` request."""

    def fault(self) -> None:
        raise RuntimeError("the test plug-in was asked to fail")


class SlowPlugin(EchoPlugin):
    """Answers correctly after burning `settings["cpu_s"]` seconds of CPU time (default 0.2)."""

    def process(self, frame: StereoImages, request: Any) -> ReferencingResult:
        end = time.process_time() + float(self.settings.get("cpu_s", 0.2))
        while time.process_time() < end:
            pass
        return super().process(frame, request)


class BrokenPlugin(EchoPlugin):
    """Fails in `configure`."""

    def configure(self, settings: Mapping[str, Any]) -> None:
        raise ValueError("this plug-in never starts")


class UnpicklableResultPlugin(EchoPlugin):
    """Answers a `FAULT` request with a result that holds a lambda (which no pipe can carry)."""

    def process(self, frame: StereoImages, request: Any) -> ReferencingResult:
        result = super().process(frame, None)
        if request == FAULT:
            result.details["callback"] = lambda: None
        return result


class StartsOncePlugin(SegfaultingPlugin):
    """Creates `settings["marker"]` in `configure`, and refuses to configure when it exists."""

    def configure(self, settings: Mapping[str, Any]) -> None:
        marker = Path(settings["marker"])
        if marker.exists():
            raise RuntimeError(f"{marker} exists: configured once already")
        marker.touch()
        super().configure(settings)
