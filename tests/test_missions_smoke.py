"""Every mission in missions/ is validated and simulated."""

import pytest
from conftest import MISSIONS

from mission import load_mission, simulate
from mission.errors import MissionError, UnsupportedMissionError
from mission.language import validate_mission_file
from mission.sim.run import check_supported

ALL = sorted(MISSIONS.glob("*.yaml"))
EXPECTED_ABORT = {"geofence_abort.yaml"}
NEEDS_PLUGINS = {"sps_field_inspection.yaml"}  # until the perception plug-ins land


def test_there_are_missions():
    assert len(ALL) >= 3


@pytest.mark.parametrize("path", ALL, ids=[p.name for p in ALL])
def test_mission_validates_and_simulates(path, tmp_path):
    mission, diags = validate_mission_file(path)
    if path.name in NEEDS_PLUGINS:
        assert diags and all("is not installed" in d.message for d in diags)
        with pytest.raises(MissionError):
            load_mission(path)
        return
    assert diags == []
    assert mission is not None
    try:
        check_supported(mission)
    except UnsupportedMissionError:
        pytest.fail(f"{path.name} uses kinds with no agent")
    result = simulate(mission, out=tmp_path / "run", plots=True)
    m = result.metrics
    assert m["aborted"] == (path.name in EXPECTED_ABORT)
    assert m["completed"] == (path.name not in EXPECTED_ABORT)
    for name in ("mission.yaml", "world.yaml", "trajectory.csv", "events.jsonl", "metrics.json",
                 "plots/map.png", "plots/profile.png", "plots/navigation.png"):
        assert (tmp_path / "run" / name).is_file(), name
    # Surveys of the reference world find every object >= 1 m tall within 2 m, with no false alarm.
    for element in m["elements"]:
        if element["kind"] == "survey":
            assert element["missed"] == [] and element["false_alarms"] == 0
            assert all(d["position_error_m"] <= 2.0 for d in element["detections"])
            assert element["coverage_percent"] >= 99.0
            assert (tmp_path / "run" / "plots" / f"survey_{element['id']}.png").is_file()
    # The mission as run is itself a valid mission with the same route.
    again = load_mission(tmp_path / "run" / "mission.yaml")
    assert [e.id for e in again.route] == [e.id for e in mission.route]
    assert again.seed == m["seed"]


def test_reference_mission_is_refused_for_its_unsupported_kinds_only():
    import yaml

    from mission.language.models import Mission

    path = MISSIONS / "sps_field_inspection.yaml"
    data = yaml.safe_load(path.read_text())
    data.pop("plugins")
    mission = Mission.model_validate(data)
    with pytest.raises(UnsupportedMissionError) as err:
        check_supported(mission)
    message = str(err.value)
    assert "explore, inspect" in message and "survey" not in message.split("(used by")[0]
    assert "\n" not in message
