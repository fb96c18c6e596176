"""Small rendered stereo views of the bench's wellhead-x scene, shared by the reconstruction tests."""

from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass

os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("MESA_SHADER_CACHE_DIR", tempfile.mkdtemp(prefix="mesa-cache-"))

import numpy as np  # noqa: E402

from mission.bench.reconstruction_scenes import (  # noqa: E402
    TruthPart,
    exposed_surface,
    ring_views,
    scene_world,
    truth_parts,
)

WIDTH, HEIGHT, FX, BASELINE = 480, 360, 400.0, 0.25


@dataclass(frozen=True, eq=False)
class Views:
    frames: list[object]
    poses: list[np.ndarray]
    parts: list[TruthPart]
    exposed: np.ndarray
    bounds: tuple[np.ndarray, np.ndarray]


def render_views(rings: tuple[tuple[float, int], ...] = ((30.0, 4), (65.0, 2)), distance: float = 5.0) -> Views:
    from mission.language.models import Stereo
    from mission.sim.camera import Degradations, StereoCamera

    world = scene_world("wellhead-x")
    parts = truth_parts(world)
    exposed = exposed_surface(parts, spacing=0.03)
    target = 0.5 * (exposed.min(axis=0) + exposed.max(axis=0))
    poses = ring_views(target, distance, rings)
    with StereoCamera(world, Stereo(width=WIDTH, height=HEIGHT, fx=FX, baseline=BASELINE),
                      Degradations(noise_sigma=1.0, seed=1)) as camera:
        frames: list[object] = [camera.render(T) for T in poses]
    bounds = (exposed.min(axis=0) - 0.4, exposed.max(axis=0) + 0.4)
    return Views(frames, poses, parts, exposed, bounds)
