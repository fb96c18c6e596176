"""Rendered stereo sequences with known poses, for visual odometry tests and benchmarks (seed 003's model scenes).

`render_sequence(poses_world_left, …)` renders a down-looking stereo pair at each given left-camera pose over a
textured seabed world; `seabed_world(…)` makes such a world (a rough sandy seabed, or a low-texture one with
`texture="mud"` and a large `scale`), and the trajectory helpers give pose sequences: `survey_trajectory` (seed 003
Table 1: speed and altitude varying, 3.5–8 m above the bottom) and `loop_trajectory` (laps over the same ground, a
trajectory that crosses itself, Table 2). Frames come lazily (`SequenceRenderer` is iterable and indexable) so long
sequences need not sit in memory.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mission.frames import Array, camera_pose
from mission.language.models import Stereo
from mission.language.world import World
from mission.plugin_api import StereoImages
from mission.sim.camera import Degradations, StereoCamera, StereoFrame
from mission.world.scene import Scene, build_scene


def seabed_world(texture: str = "sand", scale: float = 1.0, seed: int = 3, roughness: float = 0.6,
                 extent: float = 150.0, depth: float = 40.0) -> World:
    """A square seabed world (±extent m around the origin, mean depth `depth`) with no objects."""
    return World.model_validate({
        "name": "vo-seabed",
        "seabed": {"north": [-extent, extent], "east": [-extent, extent], "resolution": 1.0, "mean_depth": depth,
                   "roughness": {"amplitude": roughness, "wavelength": 12.0, "seed": seed},
                   "texture": {"kind": texture, "seed": seed, "scale": scale}},
    })


@dataclass(frozen=True)
class VehiclePath:
    """Vehicle poses sampled in time: (north, east, altitude, heading deg, pitch deg, roll deg) per sample."""

    times: Array
    states: Array

    def __len__(self) -> int:
        return len(self.times)


def survey_trajectory(duration: float = 240.0, fps: float = 25.0, speed: tuple[float, float] = (0.4, 1.2),
                      altitude: tuple[float, float] = (3.5, 8.0), turn_rate_deg: float = 5.0,
                      seed: int = 0, start: tuple[float, float] = (0.0, 0.0)) -> VehiclePath:
    """A meandering pass: speed and altitude oscillating within their ranges, the heading swinging by up to
    `turn_rate_deg` per second, small pitch and roll (±2°); starts at `start` (north, east) heading north.
    `centred_start` gives the start that centres a path on the origin (a long pass must stay over the seabed)."""
    rng = np.random.default_rng(seed)
    phase = rng.uniform(0, 2 * math.pi, 5)
    t = np.arange(int(round(duration * fps))) / fps
    v = speed[0] + (speed[1] - speed[0]) * 0.5 * (1 + np.sin(2 * np.pi * t / 37.0 + phase[0]))
    yaw_rate = turn_rate_deg * np.sin(2 * np.pi * t / 53.0 + phase[1])
    heading = np.cumsum(yaw_rate) / fps
    hd = np.radians(heading)
    north = start[0] + np.concatenate([[0.0], np.cumsum(v[:-1] * np.cos(hd[:-1]) / fps)])
    east = start[1] + np.concatenate([[0.0], np.cumsum(v[:-1] * np.sin(hd[:-1]) / fps)])
    alt = altitude[0] + (altitude[1] - altitude[0]) * 0.5 * (1 - np.cos(2 * np.pi * t / 71.0 + phase[2] * 0))
    pitch = 2.0 * np.sin(2 * np.pi * t / 9.0 + phase[3])
    roll = 2.0 * np.sin(2 * np.pi * t / 7.0 + phase[4])
    return VehiclePath(t, np.column_stack([north, east, alt, heading, pitch, roll]))


def centred_start(path: VehiclePath) -> tuple[float, float]:
    """The (north, east) start that puts the middle of `path`'s extent on the origin, for the same pass again."""
    lo, hi = path.states[:, :2].min(axis=0), path.states[:, :2].max(axis=0)
    north, east = path.states[0, :2] - 0.5 * (lo + hi)
    return float(north), float(east)


def loop_trajectory(laps: float = 3.0, radius: float = 3.0, speed: float = 0.3, altitude: float = 4.0,
                    fps: float = 10.0, wobble: float = 0.5) -> VehiclePath:
    """Laps of a circle (centre at north = radius) over the same patch of seabed, heading along the path; the
    radius wobbles by `wobble` m so that laps cross rather than retrace each other."""
    period = 2 * math.pi * radius / speed
    t = np.arange(int(round(laps * period * fps))) / fps
    a = 2 * np.pi * t / period
    r = radius + wobble * np.sin(3 * a / laps + 0.3)
    north = radius - r * np.cos(a)
    east = r * np.sin(a)
    heading = np.degrees(a)
    alt = altitude + 0.3 * np.sin(2 * a)
    return VehiclePath(t, np.column_stack([north, east, alt, heading, np.zeros_like(t), np.zeros_like(t)]))


class SequenceRenderer:
    """Renders the stereo pairs of a vehicle path over a world, one frame at a time (index or iterate)."""

    def __init__(self, world: World | Scene, path: VehiclePath, settings: Stereo | None = None,
                 degradations: Degradations | None = None, supersample: int = 1) -> None:
        """`supersample`: `StereoCamera`'s (render k× larger, average k×k blocks); 1 renders directly."""
        self.scene = world if isinstance(world, Scene) else build_scene(world)
        texture = world.seabed.texture if isinstance(world, World) else None
        self.settings = settings or Stereo(width=600, height=400, fx=500.0, baseline=0.3)
        self.camera = StereoCamera(self.scene, self.settings, degradations, texture=texture, supersample=supersample)
        self.path = path
        self.poses = np.stack([self._pose(i) for i in range(len(path))])
        """(N, 4, 4) true T_world_left of every frame."""

    def _pose(self, i: int) -> Array:
        n, e, alt, hdg, pitch, roll = self.path.states[i]
        depth = self.scene.seabed.depth_at(float(n), float(e)) - alt
        return camera_pose(float(n), float(e), float(depth), float(hdg), float(pitch), float(roll),
                           self.settings.baseline)

    def __len__(self) -> int:
        return len(self.path)

    def frame(self, i: int) -> StereoFrame:
        return self.camera.render(self.poses[i])

    def __getitem__(self, i: int) -> StereoImages:
        f = self.frame(i)
        return StereoImages(float(self.path.times[i]), f.left, f.right, f.K, f.baseline)

    def __iter__(self) -> Iterator[StereoImages]:
        for i in range(len(self)):
            yield self[i]

    def close(self) -> None:
        self.camera.close()


def render_sequence(world: World | Scene, poses_world_left: NDArray[np.float64], times: Array | None = None,
                    settings: Stereo | None = None, degradations: Degradations | None = None
                    ) -> list[StereoImages]:
    """Render a stereo pair at each given left-camera pose (T_world_left, NED world, OpenCV camera axes)."""
    scene = world if isinstance(world, Scene) else build_scene(world)
    texture = world.seabed.texture if isinstance(world, World) else None
    settings = settings or Stereo(width=600, height=400, fx=500.0, baseline=0.3)
    times = np.arange(len(poses_world_left)) / 10.0 if times is None else times
    frames = []
    with StereoCamera(scene, settings, degradations, texture=texture) as camera:
        for t, T in zip(times, poses_world_left, strict=True):
            f = camera.render(np.asarray(T, dtype=float))
            frames.append(StereoImages(float(t), f.left, f.right, f.K, f.baseline))
    return frames


__all__ = ["SequenceRenderer", "VehiclePath", "centred_start", "loop_trajectory", "render_sequence", "seabed_world",
           "survey_trajectory"]
