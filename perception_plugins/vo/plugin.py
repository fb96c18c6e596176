"""The `stereo-vo` perception plug-in: seed 003's stereo visual odometry behind the plug-in contract
(`mission.plugin_api`: configure / process / reset / close, `OdometryRequest` in, `OdometryResult` out).

The host feeds every frame the vehicle captures; the plug-in pushes it into an `Odometer` and answers with the
left camera's pose in the chain's origin frame when that frame became a processed position, or `ok=False` when
the adaptive step skipped it (reason "skipped") or tracking was lost there (reason "tracking lost"; the odometer
dead-reckons and restarts by itself). `set_origin` (and the first frame after configure or reset) starts a new
chain — and a new reference network, whose poses lived in the old origin's frame.

Settings (`configure`): `method` (classic | klt | adaptive | network; default network: long KLT tracking every
frame, cheap enough for 1200×900 at 10 Hz, with the reference network that re-localises a hovering or
manoeuvring vehicle near an object), optional odometer options (see `trajectory.settings_for`) at the top level or
under `vo`, and the mission's `sensors.stereo.rate_hz` as the frame rate; other keys are ignored.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from mission.plugin_api import OdometryRequest, OdometryResult, StereoImages
from perception_plugins.vo.errors import VoError
from perception_plugins.vo.odometer import Odometer, OdometerSettings
from perception_plugins.vo.trajectory import METHODS, settings_for

_OPTION_KEYS = {"step", "fragment_steps", "fragment_rotation_deg", "calibrate_offset", "overlap_percent",
                "max_step", "min_features", "min_track", "refresh_features", "features", "crop", "threshold_px",
                "fps", "altitude", "prefilter_px", "tracking_lowpass_px", "reference_every", "bind_overlap",
                "bind_min_inliers", "chain_margin", "formation_frames"}


class StereoOdometryPlugin:
    """Stereo visual odometry (seed 003) as a perception plug-in (see the module docstring)."""

    name = "stereo-vo"

    def __init__(self) -> None:
        self.method = "network"
        self.settings: OdometerSettings = settings_for(self.method)
        self._odometer: Odometer | None = None
        self._index = 0

    def configure(self, settings: Mapping[str, Any]) -> None:
        method = str(settings.get("method", "network"))
        if method not in METHODS:
            raise VoError(f"unknown VO method '{method}' (available: {', '.join(METHODS)})")
        options: dict[str, Any] = {k: v for k, v in settings.items() if k in _OPTION_KEYS}
        nested = settings.get("vo")
        if isinstance(nested, Mapping):
            options.update({k: v for k, v in nested.items() if k in _OPTION_KEYS})
        sensors = settings.get("sensors")
        stereo = sensors.get("stereo") if isinstance(sensors, Mapping) else None
        if "fps" not in options and isinstance(stereo, Mapping) and stereo.get("rate_hz"):
            options["fps"] = float(stereo["rate_hz"])
        self.method, self.settings = method, settings_for(method, **options)
        self.reset()

    def process(self, frame: StereoImages, request: Any = None) -> OdometryResult:
        req = request if isinstance(request, OdometryRequest) else OdometryRequest()
        if req.set_origin or self._odometer is None:
            self._odometer, self._index = Odometer(self.settings), 0
        index = self._index
        self._index += 1
        estimates = self._odometer.push(index, frame, altitude=req.altitude)
        stats = self._odometer.stats
        mine = next((e for e in estimates if e.index == index), None)
        if mine is None:
            return OdometryResult.lost("skipped", pending=self._odometer.pending(), method=self.method)
        details = {"method": self.method, "losses": stats.losses, "bindings": stats.bindings,
                   "bound_to": mine.bound_to}
        if mine.lost:
            return OdometryResult(False, mine.T_origin_cam.copy(), 0, stats.positions,
                                  {"reason": "tracking lost", **details})
        return OdometryResult(True, mine.T_origin_cam.copy(), mine.tracked, stats.positions, details)

    def reset(self) -> None:
        self._odometer, self._index = None, 0

    def close(self) -> None:
        self.reset()


__all__ = ["StereoOdometryPlugin"]
