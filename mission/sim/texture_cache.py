"""The procedural textures as the renderer takes them (uint8 texels), made once per spec and kept: in memory for
the process, and on disk under `$AUV_CACHE_DIR` (default `~/.cache/auv-mission`) for later runs, so that a run
does not spend seconds of FFTs re-making the seabed it made last time (measured: 8 of the 17 s of a referencing
run's start-up on a loaded machine). A texture is a pure function of its spec and of `mission/sim/textures.py`,
whose source is part of the key: an edited generator never reads a stale texture. A cache that cannot be written
(a read-only home) only costs the time; files are written whole (temp file, rename), so concurrent runs of a
campaign share them safely."""

from __future__ import annotations

import hashlib
import inspect
import os
from collections.abc import Callable
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mission.language.world import Texture
from mission.sim import textures
from mission.sim.textures import object_albedo, seabed_albedo, to_bytes

_MEMORY: dict[str, NDArray[np.uint8]] = {}


def cache_dir() -> Path:
    return Path(os.environ.get("AUV_CACHE_DIR") or Path.home() / ".cache" / "auv-mission") / "textures"


@cache
def _generator_version() -> str:
    return hashlib.sha256(inspect.getsource(textures).encode("utf-8")).hexdigest()[:16]


def _cached(key: str, make: Callable[[], NDArray[Any]]) -> NDArray[np.uint8]:
    digest = hashlib.sha256(f"{_generator_version()}|{key}".encode()).hexdigest()[:24]
    if digest in _MEMORY:
        return _MEMORY[digest]
    path = cache_dir() / f"{digest}.npy"
    try:
        data: NDArray[np.uint8] = np.asarray(np.load(path, allow_pickle=False), dtype=np.uint8)
    except (OSError, ValueError):
        data = to_bytes(make())
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp = path.with_name(f"{path.stem}.{os.getpid()}.tmp.npy")
            np.save(tmp, data, allow_pickle=False)
            os.replace(tmp, path)
        except OSError:
            pass
    _MEMORY[digest] = data
    return data


def seabed_texels(texture: Texture, texels: int, tile_m: float) -> NDArray[np.uint8]:
    """`to_bytes(seabed_albedo(texture, texels, tile_m))`, cached."""
    key = f"seabed|{texture.model_dump_json()}|{texels}|{tile_m!r}"
    return _cached(key, lambda: seabed_albedo(texture, texels, tile_m))


def object_texels(seed: int, texels: int, tile_m: float) -> NDArray[np.uint8]:
    """`to_bytes(object_albedo(seed, texels, tile_m))` as RGB (the grey in every channel), cached."""
    return _cached(f"object|{seed}|{texels}|{tile_m!r}",
                   lambda: np.repeat(object_albedo(seed, texels, tile_m)[..., None], 3, axis=2))
