"""Viewpoints and the scanner frustum for next-best-view scanning (seed 002 §2.2.2).

A view is a position (north, east, down) with a heading (degrees clockwise from north) and a pitch (degrees,
positive nose up) of a forward-looking 3-D scanner (laser or structured light) with a field of view
`fov_deg = (horizontal, vertical)` and a maximum range, as in the mission's `scanner` settings. Its rays form a
pinhole grid (equal steps of tan(angle)) across the frustum.

>>> s = Scanner(fov_deg=(90.0, 60.0), max_range=10.0, rays=(3, 3))
>>> d = s.directions(np.array([0.0]), np.array([0.0]))[0]
>>> d[4].round(6).tolist()                        # the centre ray looks north
[1.0, 0.0, 0.0]
>>> d[5].round(3).tolist()                        # right edge of the middle row: 45° to starboard (east)
[0.707, 0.707, 0.0]
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]


@dataclass(frozen=True)
class View:
    """One viewpoint."""

    position: tuple[float, float, float]
    heading_deg: float = 0.0
    pitch_deg: float = 0.0

    @classmethod
    def at(cls, position: ArrayLike, heading_deg: float = 0.0, pitch_deg: float = 0.0) -> View:
        p = np.asarray(position, dtype=float).reshape(3)
        return cls((float(p[0]), float(p[1]), float(p[2])), float(heading_deg), float(pitch_deg))

    @property
    def point(self) -> Array:
        return np.asarray(self.position, dtype=float)


@dataclass(frozen=True)
class Views:
    """A batch of viewpoints: positions (N, 3), headings and pitches (N,) in degrees."""

    positions: Array
    heading_deg: Array
    pitch_deg: Array

    def __len__(self) -> int:
        return len(self.positions)

    def __getitem__(self, i: int) -> View:
        return View.at(self.positions[i], float(self.heading_deg[i]), float(self.pitch_deg[i]))

    @classmethod
    def of(cls, views: list[View]) -> Views:
        if not views:
            return cls(np.zeros((0, 3)), np.zeros(0), np.zeros(0))
        return cls(np.array([v.position for v in views], dtype=float),
                   np.array([v.heading_deg for v in views], dtype=float),
                   np.array([v.pitch_deg for v in views], dtype=float))

    def select(self, mask: ArrayLike) -> Views:
        m = np.asarray(mask)
        return Views(self.positions[m], self.heading_deg[m], self.pitch_deg[m])


@dataclass(frozen=True)
class Scanner:
    """A frustum scanner: field of view (horizontal, vertical) in degrees, range in metres, rays (across, up)."""

    fov_deg: tuple[float, float] = (60.0, 45.0)
    max_range: float = 12.0
    rays: tuple[int, int] = field(default=(24, 18))

    def __post_init__(self) -> None:
        if not (0 < self.fov_deg[0] < 180 and 0 < self.fov_deg[1] < 180):
            raise ValueError(f"fov_deg must lie in (0, 180), got {self.fov_deg}")
        if not self.max_range > 0:
            raise ValueError(f"max_range must be positive, got {self.max_range}")
        if min(self.rays) < 1:
            raise ValueError(f"rays must be positive, got {self.rays}")

    def with_rays(self, rays: tuple[int, int]) -> Scanner:
        return Scanner(self.fov_deg, self.max_range, rays)

    def body_directions(self) -> Array:
        """Unit ray directions (R, 3) in the body frame (x forward, y starboard, z down)."""
        th = np.tan(np.radians(self.fov_deg[0]) / 2.0)
        tv = np.tan(np.radians(self.fov_deg[1]) / 2.0)
        a = np.linspace(-th, th, self.rays[0]) if self.rays[0] > 1 else np.zeros(1)
        b = np.linspace(-tv, tv, self.rays[1]) if self.rays[1] > 1 else np.zeros(1)
        bb, aa = np.meshgrid(b, a, indexing="ij")
        d = np.stack([np.ones(aa.size), aa.ravel(), bb.ravel()], axis=1)
        return np.asarray(d / np.linalg.norm(d, axis=1, keepdims=True), dtype=float)

    def directions(self, heading_deg: ArrayLike, pitch_deg: ArrayLike) -> Array:
        """World (NED) ray directions (N, R, 3) for N views: body rays pitched about y, then turned about z."""
        h = np.radians(np.asarray(heading_deg, dtype=float).reshape(-1))
        p = np.radians(np.asarray(pitch_deg, dtype=float).reshape(-1))
        body = self.body_directions()
        x, y, z = body[:, 0], body[:, 1], body[:, 2]
        cp, sp = np.cos(p)[:, None], np.sin(p)[:, None]
        # Pitch up (nose up) tilts forward rays towards −down: x' = x·cos p + z·sin p, z' = −x·sin p + z·cos p.
        xp, zp = x * cp + z * sp, -x * sp + z * cp
        ch, sh = np.cos(h)[:, None], np.sin(h)[:, None]
        return np.stack([xp * ch - y * sh, xp * sh + y * ch, zp], axis=2)


def heading_pitch_towards(origin: ArrayLike, target: ArrayLike) -> tuple[Array, Array]:
    """Heading and pitch (degrees, arrays) that point the scanner's axis from origins (N, 3) at targets (N, 3)."""
    d = np.asarray(target, dtype=float).reshape(-1, 3) - np.asarray(origin, dtype=float).reshape(-1, 3)
    heading = np.degrees(np.arctan2(d[:, 1], d[:, 0])) % 360.0
    pitch = np.degrees(np.arctan2(-d[:, 2], np.hypot(d[:, 0], d[:, 1])))
    return heading, pitch
