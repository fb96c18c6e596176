"""Procedural textures are made once per spec: the cached texels equal the generator's, across processes."""

from __future__ import annotations

import subprocess
import sys

import numpy as np

from mission.language.world import Texture
from mission.sim import texture_cache
from mission.sim.textures import object_albedo, seabed_albedo, to_bytes

SCRIPT = """
import sys
from mission.language.world import Texture
from mission.sim import texture_cache, textures
calls = []
original = textures.seabed_albedo
texture_cache.seabed_albedo = lambda *a: calls.append(a) or original(*a)
data = texture_cache.seabed_texels(Texture(kind='gravel', seed=3), 128, 2.0)
print(len(calls), int(data.sum()))
"""


def test_cached_texels_are_the_generators_and_a_second_process_reads_them_back(tmp_path, monkeypatch):
    monkeypatch.setenv("AUV_CACHE_DIR", str(tmp_path))
    texture = Texture(kind="gravel", seed=3)
    first, second = (subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=120,
                                    check=True).stdout.split() for _ in range(2))
    assert first[0] == "1" and second[0] == "0"  # made once, then read from the disk
    expected = to_bytes(seabed_albedo(texture, 128, 2.0))
    assert first[1] == second[1] == str(int(expected.sum()))
    assert np.array_equal(texture_cache.seabed_texels(texture, 128, 2.0), expected)
    grey = to_bytes(object_albedo(5, 64, 1.0))
    assert np.array_equal(texture_cache.object_texels(5, 64, 1.0), np.repeat(grey[..., None], 3, axis=2))


def test_an_unwritable_cache_only_costs_the_time(tmp_path, monkeypatch):
    blocked = tmp_path / "file"
    blocked.write_text("not a folder")
    monkeypatch.setenv("AUV_CACHE_DIR", str(blocked))
    texture = Texture(kind="mud", seed=11)
    assert np.array_equal(texture_cache.seabed_texels(texture, 64, 1.0), to_bytes(seabed_albedo(texture, 64, 1.0)))
