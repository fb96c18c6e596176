"""The reference mission loads into the typed model; the JSON Schema agrees with the loader."""

import json

import jsonschema
import pytest
import yaml
from conftest import MISSIONS
from pydantic import ValidationError

from mission.language import mission_schema, validate_mission_file
from mission.language.models import Mission, RouteElement

REFERENCE = MISSIONS / "sps_field_inspection.yaml"


def reference_without_plugins() -> Mission:
    data = yaml.safe_load(REFERENCE.read_text())
    data.pop("plugins")
    return Mission.model_validate(data)


def test_reference_mission_is_valid_with_its_plugins_installed():
    mission, diags = validate_mission_file(REFERENCE)
    assert diags == []
    assert mission is not None and mission.plugins.odometry == "stereo-vo"


def test_reference_mission_values_are_typed_with_units():
    m = reference_without_plugins()
    assert m.safety.max_duration == 3 * 3600
    assert m.safety.energy_reserve == 20.0
    assert m.route[1].survey is not None and m.route[1].survey.overlap == 20.0
    assert m.route[2].explore is not None and m.route[2].explore.budget == 900
    assert [e.kind for e in m.route] == ["transit", "survey", "explore", "inspect", "transit"]
    assert m.route[-1].transit is not None and m.route[-1].transit.to == "home"
    assert (m.home.north, m.home.east, m.home.depth) == (0.0, 0.0, 0.0)
    assert m.object("manifold-1").targets[0].reference == "skid-east"


def test_missions_are_immutable():
    m = reference_without_plugins()
    with pytest.raises(ValidationError):
        m.seed = 3  # type: ignore[misc]


def test_route_element_needs_exactly_one_kind():
    with pytest.raises(ValidationError, match="exactly one of"):
        RouteElement.model_validate({"id": "x"})


def test_schema_accepts_the_reference_mission_and_rejects_unknown_keys():
    schema = mission_schema()
    json.dumps(schema)
    data = yaml.safe_load(REFERENCE.read_text())
    jsonschema.validate(data, schema)
    data["vehicle"]["cruse_speed"] = 1.0
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(data, schema)


def test_a_leg_across_the_notch_of_a_non_convex_geofence_is_a_located_warning(tmp_path, capsys):
    from mission.cli import main
    from mission.language import load_mission

    path = tmp_path / "notch.yaml"
    path.write_text("""name: notch
sensors:
  usbl: {sigma: 1.5}
safety:
  geofence: [[-60, -60], [-60, 460], [100, 460], [100, 150], [360, 150], [360, -60]]
route:
  - id: out
    transit: {to: {north: 50, east: 400}, depth: 20}
  - id: across
    transit: {to: {north: 300, east: 100}, depth: 20}
  - id: back
    transit: {to: home}
""", encoding="utf-8")
    mission, diags = validate_mission_file(path)
    assert mission is not None  # legal: the executive would abort at the fence
    assert [(d.line, d.col, d.warning) for d in diags] == [(10, 19, True)]
    assert "leg of 'across' from (50, 400) to (300, 100) crosses outside the geofence" in diags[0].message
    assert load_mission(path).route[1].id == "across"
    assert main(["validate", str(path)]) == 0
    assert "warning: the leg of 'across'" in capsys.readouterr().out
    # the leg home from (300, 100) stays inside; a convex fence never warns
    path.write_text(path.read_text().replace("[100, 460], [100, 150], [360, 150], ", "[360, 460], "))
    assert validate_mission_file(path)[1] == []
