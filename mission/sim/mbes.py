"""The simulated multibeam echo-sounder (MBES) of seed 002 §2.1: a fan of beams ray-cast against the world.

The survey of seed 002 §2.1 maps the seabed and the objects on it with an MBES whose beams fan across track.
Here the fan lies in the vehicle's body y–z plane (body x forward, y starboard, z down), centred on body +z;
beam angle θ is measured from body +z towards starboard, so a beam's body direction is (0, sin θ, cos θ).
The vehicle's heading, pitch and roll (`mission.frames.rotation_zyx`) turn the fan into the world. The whole fan
is cast in one `mujoco.mj_multiRay` call against the scene's MuJoCo model (`mission.sim.mjworld`).

Each return's range gets Gaussian noise of `range_sigma`. A beam with nothing within `max_range` is a
no-return: its range is NaN, `hit` is False, its endpoint is the point at `max_range` along the beam (where an
occupancy map stops carving free space) and its object id is "".

Ping rate: a ping must wait for the echo from `max_range` before the next, so the rate cannot exceed
c / (2·max_range) with c = 1500 m/s. A configured `rate_hz` above that is clamped: `effective_rate_hz` is
min(rate_hz, max_ping_rate), and the simulator pings at that rate.

>>> Multibeam.max_rate_for(75.0)
10.0
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mission.frames import Array, rotation_zyx
from mission.language.models import Mbes
from mission.sim.mjworld import MjWorld

SOUND_SPEED = 1500.0
"""Speed of sound in sea water (m/s) used for the ping-rate limit."""


@dataclass(frozen=True, eq=False)
class Ping:
    """One MBES ping in the world NED frame; every array has one row per beam (arrays are read-only)."""

    ranges: Array
    """(N,) slant range (m) with noise; NaN for a no-return."""
    hit: NDArray[np.bool_]
    """(N,) True where the beam returned within `max_range`."""
    angles_deg: Array
    """(N,) across-track beam angles in the body frame, from body +z, positive to starboard."""
    origin_ned: Array
    """(3,) the transducer position (the vehicle position)."""
    endpoints_ned: Array
    """(N, 3) the noisy return along each beam; for a no-return, the point at `max_range`."""
    object_ids: NDArray[np.str_]
    """(N,) the id of the object a beam hit; "" for the seabed or a no-return."""
    directions_ned: Array
    """(N, 3) unit beam directions in the world."""


class Multibeam:
    """A multibeam echo-sounder mounted at the vehicle origin, looking down (seed 002 §2.1).

    `beams` beams spread evenly over `swath_deg` (outer beams at ±swath/2), ranges up to `max_range` metres,
    Gaussian range noise of `range_sigma` metres from a generator seeded with `seed`.
    """

    def __init__(self, world: MjWorld, beams: int = 256, swath_deg: float = 120.0, max_range: float = 80.0,
                 range_sigma: float = 0.05, rate_hz: float = 10.0, seed: int = 0) -> None:
        if beams < 1:
            raise ValueError(f"an MBES needs at least 1 beam, got {beams}")
        if not 0.0 <= swath_deg < 180.0:
            raise ValueError(f"MBES swath must be in [0, 180) degrees, got {swath_deg}")
        if not (max_range > 0.0 and math.isfinite(max_range)):
            raise ValueError(f"MBES max_range must be a positive number of metres, got {max_range}")
        if range_sigma < 0.0:
            raise ValueError(f"MBES range_sigma must be >= 0, got {range_sigma}")
        if rate_hz <= 0.0:
            raise ValueError(f"MBES rate_hz must be > 0, got {rate_hz}")
        self.world = world
        self.beams = int(beams)
        self.swath_deg = float(swath_deg)
        self.max_range = float(max_range)
        self.range_sigma = float(range_sigma)
        self.rate_hz = float(rate_hz)
        self.rng = np.random.default_rng(seed)
        self.angles_deg: Array = np.linspace(-0.5 * swath_deg, 0.5 * swath_deg, self.beams)
        self.angles_deg.setflags(write=False)
        a = np.radians(self.angles_deg)
        self._dirs_body: Array = np.stack([np.zeros_like(a), np.sin(a), np.cos(a)], axis=1)

    @classmethod
    def from_settings(cls, world: MjWorld, settings: Mbes, seed: int = 0) -> Multibeam:
        """An MBES configured by a mission's `sensors.mbes` block."""
        return cls(world, settings.beams, settings.swath_deg, settings.max_range, settings.range_sigma,
                   settings.rate_hz, seed)

    @staticmethod
    def max_rate_for(max_range: float) -> float:
        """The highest ping rate (Hz) at which the echo from `max_range` returns before the next ping."""
        return SOUND_SPEED / (2.0 * max_range)

    @property
    def max_ping_rate(self) -> float:
        """c / (2·max_range), in Hz."""
        return self.max_rate_for(self.max_range)

    @property
    def effective_rate_hz(self) -> float:
        """The rate the sonar actually pings at: the configured rate, clamped to `max_ping_rate`."""
        return min(self.rate_hz, self.max_ping_rate)

    @property
    def period_s(self) -> float:
        """Time between pings at the effective rate."""
        return 1.0 / self.effective_rate_hz

    def ping(self, north: float, east: float, depth: float, heading_deg: float, pitch_deg: float = 0.0,
             roll_deg: float = 0.0) -> Ping:
        """Cast the fan from the vehicle pose (NED position, attitude in degrees) and return the noisy ping."""
        origin = np.array([north, east, depth], dtype=float)
        dirs = self._dirs_body @ rotation_zyx(heading_deg, pitch_deg, roll_deg).T
        dist, geomid = self.world.cast_fan(origin, dirs, self.max_range)
        hit = (geomid >= 0) & (dist <= self.max_range)
        ranges = np.where(hit, dist, np.nan)
        if self.range_sigma > 0.0:
            ranges = np.maximum(ranges + self.rng.normal(0.0, self.range_sigma, self.beams), 0.0)
        endpoints = origin + dirs * np.where(hit, ranges, self.max_range)[:, None]
        object_ids = self.world.objects_hit(np.where(hit, geomid, -1))
        for arr in (ranges, hit, origin, endpoints, object_ids, dirs):
            arr.setflags(write=False)
        return Ping(ranges, hit, self.angles_deg, origin, endpoints, object_ids, dirs)
