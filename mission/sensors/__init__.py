"""Payload sensor drivers for `auv run`: entry points in the group `auv.sensors`, picked by the scheme of a
mission sensor's `driver:` URI.

A URI is `SCHEME:ADDRESS` (`zenoh:auv/sim?connect=tcp/127.0.0.1:7447`, `replay:runs/x/stereo`,
`camera:0,1?calibration=cam.yaml`). The entry point named SCHEME is a factory
`open_driver(address, context) -> SensorDriver`. A driver runs in its own thread (or process) and hands each
frame to `context.sink`: a `SonarPing` (sensor `mbes`), `ScanFrame` (`scanner`) or `StereoImages` (`stereo`),
stamped with the sensor's own time. Pings and scans leave the driver with NaN pose fields: the onboard vehicle
places them with its navigation estimate interpolated to the stamp (`mission.sensors.navtrack`). `request`
tells the driver whether the executive wants the sensor on, and at what frame rate (stereo); it never blocks.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from importlib.metadata import entry_points
from typing import Any, Protocol
from urllib.parse import parse_qs

from mission.errors import AuvError
from mission.language.models import Mbes, Scanner, Stereo
from mission.plugin_api import StereoImages
from mission.vehicle import ScanFrame, SonarPing

GROUP = "auv.sensors"
SENSOR_NAMES = ("mbes", "stereo", "scanner")
NO_POSE = math.nan  # the pose fields of a ping or scan as a driver delivers it

SensorFrame = SonarPing | ScanFrame | StereoImages
SensorSettings = Mbes | Stereo | Scanner
FRAME_TYPES: dict[str, type] = {"mbes": SonarPing, "stereo": StereoImages, "scanner": ScanFrame}


class SensorError(AuvError):
    """A sensor driver cannot be found, opened, or read (unknown scheme, missing folder or device)."""


@dataclass(frozen=True)
class DriverContext:
    """What a driver is given: which sensor it feeds (`mbes`, `stereo`, `scanner`), that sensor's settings from
    the mission, and `sink(frame)`, safe to call from any thread, that takes each frame."""

    sensor: str
    settings: SensorSettings
    sink: Callable[[SensorFrame], None]


class SensorDriver(Protocol):
    """A running stream. `request(on, rate_hz)` asks for the sensor on or off (and a stereo frame rate; None: the
    sensor's own); `close()` stops the driver's threads and releases the source."""

    def request(self, on: bool, rate_hz: float | None) -> None: ...

    def close(self) -> None: ...


DriverFactory = Callable[[str, DriverContext], SensorDriver]


def installed_drivers() -> dict[str, str]:
    """Installed drivers: scheme → entry-point value."""
    return {ep.name: ep.value for ep in entry_points(group=GROUP)}


def split_driver_uri(uri: str) -> tuple[str, str]:
    """`zenoh:auv/sim?connect=tcp/127.0.0.1:7447` → (`zenoh`, `auv/sim?connect=tcp/127.0.0.1:7447`).

    >>> split_driver_uri("replay:runs/demo/stereo")
    ('replay', 'runs/demo/stereo')
    """
    scheme, sep, address = uri.partition(":")
    if not sep or not scheme or not address:
        raise SensorError(f"sensor driver URI '{uri}' is not SCHEME:ADDRESS (e.g. zenoh:auv/sim)")
    return scheme, address


def split_query(address: str) -> tuple[str, dict[str, str]]:
    """`auv/sim?connect=tcp/127.0.0.1:7447` → (`auv/sim`, {`connect`: `tcp/127.0.0.1:7447`}).

    >>> split_query("0,1?calibration=cam.yaml&fps=10")
    ('0,1', {'calibration': 'cam.yaml', 'fps': '10'})
    """
    path, _, query = address.partition("?")
    return path, {k: v[-1] for k, v in parse_qs(query, keep_blank_values=True).items()}


def open_driver(uri: str, context: DriverContext) -> SensorDriver:
    """Find the driver for the URI's scheme and start it (see the module docstring)."""
    scheme, address = split_driver_uri(uri)
    eps = {ep.name: ep for ep in entry_points(group=GROUP)}
    if scheme not in eps:
        known = ", ".join(sorted(eps)) or "none"
        raise SensorError(f"no sensor driver for scheme '{scheme}' (installed: {known})")
    try:
        factory: Any = eps[scheme].load()
    except Exception as exc:  # a broken driver package (or its missing extra) is the user's environment
        raise SensorError(f"sensor driver '{scheme}' failed to load: {exc!r}") from exc
    driver: SensorDriver = factory(address, context)
    return driver
