"""Target viewpoints that the database shows below the minimum altitude are warnings at the target's line
(`mission.language.viewpoints`), before the dive."""

from __future__ import annotations

import yaml
from conftest import MISSIONS

from mission.language import validate_mission_file


def edited(tmp_path, edit) -> tuple[list, list[str]]:
    data = yaml.safe_load((MISSIONS / "sps_field_inspection.yaml").read_text(encoding="utf-8"))
    data["world"] = str(MISSIONS / data["world"])
    edit(data["objects"][0])
    path = tmp_path / "mission.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    mission, diags = validate_mission_file(path)
    assert mission is not None, [str(d) for d in diags]
    return diags, path.read_text(encoding="utf-8").splitlines()


def target_line(lines: list[str], target_id: str) -> int:
    return next(k for k, line in enumerate(lines, 1) if line.strip() == f"- id: {target_id}")


def test_the_reference_missions_viewpoints_are_all_above_the_minimum_altitude():
    _, diags = validate_mission_file(MISSIONS / "sps_field_inspection.yaml")
    assert diags == []


def test_a_standoff_below_the_minimum_altitude_is_a_warning_at_its_targets_line(tmp_path):
    def lower(obj):
        next(t for t in obj["targets"] if t["id"] == "hatch")["standoff"] = 1.0  # min_altitude is 1.5

    diags, lines = edited(tmp_path, lower)
    [d] = diags
    assert d.warning and d.line == target_line(lines, "hatch")
    # the hatch (z -2.0) sits below module-top's corners (z -2.6): 1 m above it is only 0.4 m above them
    assert "target 'hatch'" in d.message and "0.40 m above point set 'module-top'" in d.message


def test_a_taller_part_beside_a_target_forbids_its_viewpoint_and_the_warning_names_it(tmp_path):
    def taller_part(obj):
        gauge = next(t for t in obj["targets"] if t["id"] == "gauge-west")  # viewpoint 2.5 m above z -0.2
        x, y = gauge["at"][0], gauge["at"][1]
        obj["characteristic_points"].append(
            {"id": "pump-head", "points": [[x + 0.5, y, -1.8], [x + 0.5, y + 0.6, -1.8], [x + 1.0, y, -1.9]]})

    diags, lines = edited(tmp_path, taller_part)
    [d] = diags
    assert d.warning and d.line == target_line(lines, "gauge-west")
    assert "point set 'pump-head'" in d.message and "0.80 m above" in d.message  # the highest of them, 1.9 m up
