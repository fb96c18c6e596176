"""Extreme numbers in every numeric field of the reference mission and its world (found by walking their
structure): out-of-range values are refused where they stand, never with a traceback; values that validate also
simulate (on a tiny mission that ends within a minute of mission time) without an arithmetic error."""

from __future__ import annotations

import copy
import math
import re
from pathlib import Path
from typing import Any

import pytest
import yaml
from hostile_support import run_auv, write_tiny

from mission.language import limits, validate_mission_file
from mission.language.source import PathKey, parse_yaml

ROOT = Path(__file__).resolve().parents[3]
REFERENCE = ROOT / "missions" / "sps_field_inspection.yaml"
REFERENCE_WORLD = ROOT / "worlds" / "sps_field.yaml"
HOSTILE = {"1e308": 1e308, "-1e308": -1e308, "nan": math.nan, "inf": math.inf}


def numeric_paths(node: Any, path: PathKey = ()) -> list[PathKey]:
    """Paths of every number (not booleans) in a plain YAML value."""
    if isinstance(node, bool):
        return []
    if isinstance(node, int | float):
        return [path]
    if isinstance(node, dict):
        return [p for k, v in node.items() for p in numeric_paths(v, path + (k,))]
    if isinstance(node, list):
        return [p for i, v in enumerate(node) for p in numeric_paths(v, path + (i,))]
    return []


def replaced(data: Any, paths: list[PathKey], value: float) -> Any:
    out = copy.deepcopy(data)
    for path in paths:
        node = out
        for part in path[:-1]:
            node = node[part]
        node[path[-1]] = value
    return out


def write(path: Path, data: Any) -> dict[PathKey, int]:
    """Write `data` one value a line; the line of each value path."""
    text = yaml.safe_dump(data, default_flow_style=False, sort_keys=False)
    path.write_text(text, encoding="utf-8")
    return {p: line for p, (line, _) in parse_yaml(text, str(path)).value_at.items()}


@pytest.fixture
def tiny(tmp_path: Path) -> Path:
    return write_tiny(tmp_path)


@pytest.fixture(scope="module")
def reference() -> tuple[dict[str, Any], dict[str, Any]]:
    mission = yaml.safe_load(REFERENCE.read_text(encoding="utf-8"))
    world = yaml.safe_load(REFERENCE_WORLD.read_text(encoding="utf-8"))
    return mission, world


def error_lines(diags: list[Any], file: Path) -> set[int]:
    return {d.line for d in diags if not d.warning and Path(d.file) == file}


@pytest.mark.parametrize("side", ["mission", "world"])
@pytest.mark.parametrize("name", list(HOSTILE))
def test_every_number_of_the_reference_mission_out_of_range_is_refused_on_its_own_line(tmp_path, reference,
                                                                                      name, side):
    mission, world = reference
    world_path, mission_path = tmp_path / "world.yaml", tmp_path / "mission.yaml"
    if side == "world":
        world = replaced(world, numeric_paths(world), HOSTILE[name])
    else:
        mission = replaced(mission, numeric_paths(mission), HOSTILE[name])
    world_lines = write(world_path, world)
    mission_lines = write(mission_path, mission | {"world": str(world_path)})
    outcome = run_auv("validate", mission_path)
    assert outcome.code == 1 and "Traceback" not in outcome.output, outcome.output[-3000:]
    printed: dict[str, set[int]] = {}
    for file, line in re.findall(r"^(.+?):(\d+):\d+: (?!warning)", outcome.output, re.M):
        printed.setdefault(file, set()).add(int(line))
    file, lines, paths = ((world_path, world_lines, numeric_paths(world)) if side == "world" else
                          (mission_path, mission_lines, numeric_paths(mission)))
    missed = [p for p in paths if lines[p] not in printed.get(str(file), set())]
    assert missed == [], f"{file.name}: no error at {missed[:10]}"


@pytest.mark.parametrize("value", [1e308, 1e-300], ids=["1e308", "1e-300"])
def test_each_number_of_the_reference_mission_alone_never_escapes_as_an_exception(tmp_path, reference, value):
    """One field at a time, so that the cross-checks run on everything else (where divisions and products
    happen): validation returns diagnostics, and a value past any bound is refused at its own line."""
    mission, world = reference
    world_path, mission_path = tmp_path / "world.yaml", tmp_path / "mission.yaml"
    write(world_path, world)
    base = mission | {"world": str(world_path)}
    for path in numeric_paths(mission):
        lines = write(mission_path, replaced(base, [path], value))
        _, diags = validate_mission_file(mission_path)
        if value > 1e300:
            assert lines[path] in error_lines(diags, mission_path), path
    write(mission_path, base)
    for path in numeric_paths(world):
        lines = write(world_path, replaced(world, [path], value))
        _, diags = validate_mission_file(mission_path)
        if value > 1e300:
            assert lines[path] in error_lines(diags, world_path), path


def with_value_where_valid(tiny: Path, value: float) -> list[PathKey]:
    """Put `value` in each numeric field of the tiny world, then of the tiny mission, in turn, keeping it where the
    whole still validates; the fields that kept it (the files are left with all of them)."""
    world_path = tiny.parent / "tiny_world.yaml"
    mission, world = yaml.safe_load(tiny.read_text()), yaml.safe_load(world_path.read_text())
    mission["world"] = str(world_path)
    kept: list[PathKey] = []
    for path in numeric_paths(world):
        write(world_path, replaced(world, [path], value))
        if validate_mission_file(tiny)[0] is not None:
            world, kept = replaced(world, [path], value), kept + [("world",) + path]
    write(world_path, world)
    for path in numeric_paths(mission):
        write(tiny, replaced(mission, [path], value))
        if validate_mission_file(tiny)[0] is not None:
            mission, kept = replaced(mission, [path], value), kept + [path]
    write(tiny, mission)
    return kept


def test_tiny_numbers_that_validate_also_simulate(tiny):
    """1e-300 in every field of the tiny mission and world where it validates (positions, headings, sigmas,
    currents, slopes...), then simulated. (1e308 validates nowhere: see the reference mission's tests.)"""
    kept = with_value_where_valid(tiny, 1e-300)
    assert len(kept) > 30
    assert ("vehicle", "max_speed") not in kept and ("world", "seabed", "resolution") not in kept
    checked = run_auv("validate", tiny)
    assert checked.code == 0 and "Traceback" not in checked.output, checked.output[-3000:]
    outcome = run_auv("simulate", tiny, "--no-plots", "--quiet", "--out", tiny.parent / "run")
    assert outcome.code in (0, 1) and "Traceback" not in outcome.output, outcome.output[-3000:]
    assert "tiny:" in outcome.output and "mission time" in outcome.output, outcome.output


def test_the_largest_legal_values_simulate(tiny):
    world = tiny.parent / "tiny_world.yaml"
    world.write_text(world.read_text().replace("north: 0.1, east: -0.05", f"north: {limits.MAX_CURRENT}, "
                                               f"east: {-limits.MAX_CURRENT}")
                     .replace("resolution: 1.0", "resolution: 0.0601").replace("wavelength: 10", "wavelength: 0.5"))
    tiny.write_text(tiny.read_text().replace("max_speed: 2.0, cruise_speed: 1.5", f"max_speed: {limits.MAX_SPEED}, "
                                             f"cruise_speed: {limits.MAX_SPEED}")
                    .replace("max_acceleration: 0.2", f"max_acceleration: {limits.MAX_ACCELERATION}")
                    .replace("max_yaw_rate: 15", f"max_yaw_rate: {limits.MAX_YAW_RATE}")
                    .replace("max_vertical_speed: 0.5", f"max_vertical_speed: {limits.MAX_VERTICAL_SPEED}")
                    .replace("speed: 1.0", f"speed: {limits.MAX_SPEED}"))
    checked = run_auv("validate", tiny)
    assert checked.code == 0, checked.output
    outcome = run_auv("simulate", tiny, "--no-plots", "--quiet", "--out", tiny.parent / "run")
    assert outcome.code in (0, 1) and "Traceback" not in outcome.output, outcome.output[-3000:]
    assert "tiny:" in outcome.output


def test_the_slowest_legal_vehicle_ends_within_max_duration_and_abort_time(tiny):
    tiny.write_text(tiny.read_text().replace("max_speed: 2.0, cruise_speed: 1.5", f"max_speed: {limits.MIN_SPEED}, "
                                             f"cruise_speed: {limits.MIN_SPEED}")
                    .replace("speed: 1.0", f"speed: {limits.MIN_SPEED}"))
    outcome = run_auv("simulate", tiny, "--no-plots", "--quiet", "--out", tiny.parent / "run")
    assert outcome.code == 1 and "Traceback" not in outcome.output, outcome.output[-3000:]
    seconds = float(re.search(r"; (\d+) s mission time", outcome.output)[1])  # type: ignore[index]
    assert seconds <= 60 + 30 + 1  # max_duration + abort_time, and a tick
