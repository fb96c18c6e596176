"""Plug-in results that come late (an onboard host runs perception outside the control loop): the inspection
still photographs its targets within 0.1 m of their viewpoints, against the simulator's truth."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from doubles import LateCall

from mission import load_mission, simulate

ROOT = Path(__file__).resolve().parents[2]
DELAYS = {"referencing": 1.5, "odometry": 0.7}  # seconds of vehicle time: several control ticks, a few frames


def delayed_mission(folder: Path) -> Path:
    """The manifold inspection of the docs, reduced to the targets referenced to module-top (the set that is
    recognised from above) and without the way home."""
    data = yaml.safe_load((ROOT / "docs" / "missions" / "manifold_inspection.yaml").read_text(encoding="utf-8"))
    data["world"] = str(ROOT / "worlds" / "sps_field.yaml")
    data["safety"]["max_duration"] = "20min"
    data["route"] = [e for e in data["route"] if e["id"] != "home"]
    data["route"][1]["inspect"]["targets"] = ["hatch"]
    path = folder / "delayed.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    pytest.importorskip("cv2")
    path = delayed_mission(tmp_path_factory.mktemp("delayed"))
    from mission.plugin_host import PluginHost

    late: list[LateCall] = []

    class DelayedHost(PluginHost):
        """The real host (plug-ins in their workers), each result withheld `DELAYS[role]` seconds more."""

        def submit(self, role, frame, request, now):
            late.append(LateCall(super().submit(role, frame, request, now), now + DELAYS.get(role, 0.0)))
            return late[-1]

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr("mission.sim.run.PluginHost", DelayedHost)
        result = simulate(load_mission(path), plots=False)
    assert late, "the simulation did not use the delayed host"
    return result


def test_late_plug_in_results_still_photograph_every_target_within_tolerance(run):
    element = next(e for e in run.metrics["elements"] if e["id"] == "photograph-manifold")
    assert element["status"] == "succeeded", element.get("reason")
    assert element["targets_ok"] == 1 and element["targets"]["hatch"]["photos"] == 2
    for photo in element["photos"]:
        assert photo["camera_error_m"] <= 0.1 and photo["target_in_image"]


def test_late_results_are_used_at_their_frames_time(run):
    element = next(e for e in run.metrics["elements"] if e["id"] == "photograph-manifold")
    assert element["vo"]["frames"] > 0 and element["vo"]["camera_error_max_m"] < 0.1
    fused = [a for a in element["attempts"] if a["stage"] == "fused"]
    assert fused and all(a["position_error_m"] < 0.05 for a in fused)
