"""Shared fixtures: paths of the repository's worlds and missions, and a writer for small test missions."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
WORLD = ROOT / "worlds" / "sps_field.yaml"
MISSIONS = ROOT / "missions"

os.environ.setdefault("MPLBACKEND", "Agg")
os.environ.setdefault("MESA_SHADER_CACHE_DIR", tempfile.mkdtemp(prefix="mesa-cache-"))

HEADER = f"""
world: {WORLD}
sensors:
  usbl: {{sigma: 1.5, rate_hz: 0.5}}
  dvl: {{drift_percent: 0.5}}
safety:
  geofence: [[-60, -60], [-60, 460], [360, 460], [360, -60]]
  max_depth: 120
  min_altitude: 1.5
"""


@pytest.fixture
def write_mission(tmp_path: Path):
    """Write a mission file: `write_mission("name", route_yaml, extra_yaml="")` → its path."""

    def write(name: str, route: str, extra: str = "", header: str = HEADER) -> Path:
        path = tmp_path / f"{name}.yaml"
        path.write_text(f"name: {name}\n{header}\n{extra}\nroute:\n{route}", encoding="utf-8")
        return path

    return write
