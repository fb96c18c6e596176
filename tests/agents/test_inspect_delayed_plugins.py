"""Plug-in results that come late (an onboard host runs perception outside the control loop): the inspection
still photographs its targets within 0.1 m of their viewpoints, against the simulator's truth."""

from __future__ import annotations

from pathlib import Path

import pytest
from doubles import DelayedHost

from mission import load_mission, simulate

ROOT = Path(__file__).resolve().parents[2]
DELAYS = {"referencing": 1.5, "odometry": 0.7}  # seconds of vehicle time: several control ticks, a few frames

MISSION = f"""
name: delayed-inspection
world: {ROOT / "worlds" / "sps_field.yaml"}
seed: 5
vehicle: {{cruise_speed: 1.5, max_speed: 2.0, turn_radius: 6}}
sensors:
  stereo: {{width: 1200, height: 900, fx: 1000, baseline: 0.25, rate_hz: 10, max_range: 8}}
  usbl:   {{sigma: 1.5, rate_hz: 0.5}}
  dvl:    {{drift_percent: 0.5}}
plugins: {{referencing: stereo-referencing, odometry: stereo-vo}}
safety:
  geofence: [[-60, -60], [-60, 460], [360, 460], [360, -60]]
  max_depth: 120
  min_altitude: 1.5
  max_duration: 20min
objects:
  - id: manifold-1
    pose: {{north: 150, east: 200, depth: 58, heading: 30}}
    size: [8, 5, 2.5]
    characteristic_points:
      - id: module-top
        points: [[2, 1, -2], [6, 1, -2], [6, 4, -2], [2, 4, -2], [4, 2.5, -2.6]]
    targets:
      - {{id: hatch, at: [4.0, 2.5, -2.0], reference: module-top, standoff: 3.0, photos: 2}}
      - {{id: hatch-east, at: [5.5, 2.5, -2.0], reference: module-top, standoff: 3.0, photos: 1}}
route:
  - id: approach
    transit: {{to: {{north: 150, east: 200}}, depth: 45, navigation: usbl}}
  - id: photograph
    inspect: {{object: manifold-1, targets: all, order: auto, search: {{pattern: expanding-square, budget: 5min}}}}
    actions: [photograph]
"""


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    pytest.importorskip("cv2")
    path = tmp_path_factory.mktemp("delayed") / "delayed.yaml"
    path.write_text(MISSION, encoding="utf-8")
    hosts: list[DelayedHost] = []

    def delayed_host(*args, **kwargs):
        hosts.append(DelayedHost(*args, delays=DELAYS, **kwargs))
        return hosts[-1]

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr("mission.sim.run.PluginHost", delayed_host)
        result = simulate(load_mission(path), plots=False)
    assert hosts, "the simulation did not use the delayed host"
    return result


def test_late_plug_in_results_still_photograph_every_target_within_tolerance(run):
    element = next(e for e in run.metrics["elements"] if e["id"] == "photograph")
    assert element["status"] == "succeeded", element.get("reason")
    assert element["targets_ok"] == 2
    for photo in element["photos"]:
        assert photo["camera_error_m"] <= 0.1 and photo["target_in_image"]
    assert sum(1 for p in element["photos"] if p["target"] == "hatch") == 2


def test_late_results_are_used_at_their_frames_time(run):
    element = next(e for e in run.metrics["elements"] if e["id"] == "photograph")
    assert element["vo"]["frames"] > 0 and element["vo"]["camera_error_max_m"] < 0.1
    fused = [a for a in element["attempts"] if a["stage"] == "fused"]
    assert fused and all(a["position_error_m"] < 0.05 for a in fused)
