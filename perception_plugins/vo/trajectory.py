"""Whole trajectories from stereo sequences: the named methods and `estimate_trajectory`.

Methods (seed 003): `classic` — the two-position four-image scheme at a fixed step; `klt` — long KLT tracking over
fragments of `fragment_steps` steps; `adaptive` — KLT between positions chosen by the adaptive step (formula,
halving, cropping); `network` — long KLT tracking with the virtual reference network.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import fields, replace
from typing import Any

import numpy as np

from mission.plugin_api import StereoImages
from perception_plugins.vo.errors import VoError
from perception_plugins.vo.network import NetworkSettings
from perception_plugins.vo.odometer import Estimate, Odometer, OdometerSettings
from perception_plugins.vo.se3 import fill_poses

METHODS = ("classic", "klt", "adaptive", "network")

_NETWORK_KEYS = {"reference_every": "every", "bind_overlap": "overlap", "bind_min_inliers": "min_inliers",
                 "chain_margin": "chain_margin", "formation_frames": "formation_frames"}


def settings_for(method: str, **options: Any) -> OdometerSettings:
    """The odometer settings of a named method; `options` override `OdometerSettings` fields (step, fragment_steps,
    features, min_features, overlap_percent, max_step, fps, altitude, …) and the network's (reference_every,
    bind_overlap, bind_min_inliers, chain_margin, formation_frames)."""
    if method not in METHODS:
        raise VoError(f"unknown VO method '{method}' (available: {', '.join(METHODS)})")
    base = {"classic": OdometerSettings(frontend="classic", fragment_steps=1),
            "klt": OdometerSettings(frontend="klt"),
            "adaptive": OdometerSettings(frontend="klt", adaptive=True, fragment_steps=1),
            "network": OdometerSettings(frontend="klt", network=NetworkSettings())}[method]
    known = {f.name for f in fields(OdometerSettings)} - {"network", "frontend", "adaptive"}
    unknown = set(options) - known - set(_NETWORK_KEYS)
    if unknown:
        raise VoError(f"unknown VO option(s) {', '.join(sorted(unknown))} (known: "
                      f"{', '.join(sorted(known | set(_NETWORK_KEYS)))})")
    settings = replace(base, **{k: v for k, v in options.items() if k in known})
    net = {_NETWORK_KEYS[k]: v for k, v in options.items() if k in _NETWORK_KEYS}
    if net and settings.network is None:
        raise VoError(f"option(s) {', '.join(sorted(net))} need the 'network' method")
    if settings.network is not None and net:
        settings = replace(settings, network=replace(settings.network, **net))
    return settings


def run_odometer(frames: Iterable[StereoImages], odometer: Odometer,
                 progress: Callable[[int], None] | None = None) -> tuple[int, list[Estimate]]:
    """Push every frame through an odometer; returns the frame count and the estimates of processed positions."""
    estimates: list[Estimate] = []
    count = 0
    for i, frame in enumerate(frames):
        estimates.extend(odometer.push(i, frame))
        count = i + 1
        if progress is not None:
            progress(i)
    estimates.extend(odometer.finish())
    return count, estimates


def estimate_trajectory(frames: Iterable[StereoImages], method: str = "adaptive",
                        progress: Callable[[int], None] | None = None, **options: Any) -> np.ndarray:
    """(N, 4, 4) T_world_cam of the left camera for every frame (frame 0 is the identity; frames a method skips get
    poses interpolated on SE(3) between their processed neighbours)."""
    odometer = Odometer(settings_for(method, **options))
    count, estimates = run_odometer(frames, odometer, progress)
    if count == 0:
        raise VoError("no frames to estimate a trajectory from")
    return fill_poses({e.index: e.T_origin_cam for e in estimates}, count)


__all__ = ["METHODS", "estimate_trajectory", "run_odometer", "settings_for"]
