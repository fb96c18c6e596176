"""Support of the hostile-input corpus: the real `auv` command in a subprocess, under a memory limit and a time
bound, and a tiny mission with a tiny world that simulates in a second or two."""

from __future__ import annotations

import resource
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

MEMORY_LIMIT = 2 * 1024**3  # bytes of address space for each `auv` run
TIME_LIMIT = 20.0  # seconds for each `auv` run

TINY_WORLD = """\
name: tiny-world
seabed:
  north: [-60, 60]
  east: [-60, 60]
  resolution: 1.0
  mean_depth: 30
  slope: {north: 0.01, east: 0.0}
  roughness: {amplitude: 0.2, wavelength: 10, seed: 1}
  texture: {kind: sand, seed: 1, scale: 1.0}
current: {north: 0.1, east: -0.05}
objects:
  - id: box
    pose: {north: 20, east: 20, depth: 29, heading: 10, pitch: 1, roll: 1}
    offset: {north: 0.5, east: 0.5, depth: 0.1, heading: 1, pitch: 0.5, roll: 0.5}
    parts:
      - {shape: box, size: [2, 2, 1], at: [0, 0, 0], heading: 5, color: [0.5, 0.5, 0.5]}
      - {shape: cylinder, radius: 0.3, height: 1, at: [0, 0, -1], color: [0.5, 0.5, 0.5]}
"""

TINY_MISSION = """\
name: tiny
world: tiny_world.yaml
seed: 1
origin: {lat: 42.95, lon: 131.85}
home: {north: 0, east: 0, depth: 0, heading: 0}
vehicle: {max_speed: 2.0, cruise_speed: 1.5, max_acceleration: 0.2, max_yaw_rate: 15, max_vertical_speed: 0.5,
          turn_radius: 6, energy_wh: 4000, hotel_power_w: 60, propulsion_power_w: 180}
sensors:
  usbl: {sigma: 1.5, rate_hz: 0.5}
  dvl: {drift_percent: 0.5, velocity_sigma: 0.01, max_altitude: 100}
safety:
  geofence: [[-50, -50], [-50, 50], [50, 50], [50, -50]]
  max_depth: 60
  min_altitude: 1.0
  max_duration: 60
  abort_time: 30
  energy_reserve: 20
  link_timeout: 3
  on_violation: {abort_to: {north: 0, east: 0, depth: 0}}
route:
  - id: hop
    transit: {to: {north: 10, east: 5}, depth: 5, speed: 1.0, capture_radius: 3}
    timeout: 60
"""


@dataclass(frozen=True)
class Outcome:
    code: int
    output: str  # stdout and stderr together


def _limit_memory() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))


def run_auv(*args: str | Path, cwd: Path | None = None) -> Outcome:
    """`auv ARGS` in a subprocess under the memory limit; a run past the time bound fails the test."""
    try:
        done = subprocess.run([sys.executable, "-m", "mission", *map(str, args)], cwd=cwd, capture_output=True,
                              text=True, timeout=TIME_LIMIT, preexec_fn=_limit_memory)
    except subprocess.TimeoutExpired:
        pytest.fail(f"auv {' '.join(map(str, args))} ran longer than {TIME_LIMIT:.0f} s")
    return Outcome(done.returncode, done.stdout + done.stderr)


def write_tiny(folder: Path) -> Path:
    """A tiny valid mission (one short transit, a one-minute limit) beside its tiny world; its path."""
    (folder / "tiny_world.yaml").write_text(TINY_WORLD, encoding="utf-8")
    path = folder / "tiny.yaml"
    path.write_text(TINY_MISSION, encoding="utf-8")
    return path
