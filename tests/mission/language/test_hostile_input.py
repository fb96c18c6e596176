"""Hostile files given to `auv validate`: each ends within the time bound and the memory limit (`hostile_support`),
with exit code 1, a located message (FILE:LINE:COL) that says what was refused, and no traceback. Large inputs are
generated once per session, never stored."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest
from hostile_support import run_auv, write_tiny

from mission.language import limits

ROUTE = "route:\n  - id: go\n    transit: {to: home}\n"
SENSORS = "sensors:\n  usbl: {sigma: 1.5}\n"


def located(output: str, file: Path | str, text: str) -> list[str]:
    """The printed lines located in `file` (FILE:LINE:COL: ...) that contain `text`."""
    pattern = re.compile(rf"^{re.escape(str(file))}:\d+:\d+: .*{re.escape(text)}", re.MULTILINE)
    return pattern.findall(output)


def assert_refused(outcome, file: Path | str, text: str) -> None:
    assert "Traceback" not in outcome.output, outcome.output[-3000:]
    assert outcome.code == 1, outcome.output[-3000:]
    assert located(outcome.output, file, text), outcome.output[-3000:]


@pytest.fixture
def tiny(tmp_path: Path) -> Path:
    return write_tiny(tmp_path)


@pytest.fixture(scope="session")
def corpus(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The generated large inputs, written once for the session."""
    folder = tmp_path_factory.mktemp("hostile")
    bomb = ["l0: &l0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
    bomb += [f"l{i}: &l{i} [" + ", ".join([f"*l{i - 1}"] * 9) + "]" for i in range(1, 10)]
    (folder / "alias_bomb.yaml").write_text("name: bomb\n" + "\n".join(bomb) + "\n" + ROUTE)
    (folder / "nested.yaml").write_text("name: deep\nroute: " + "[" * 10_000 + "]" * 10_000 + "\n")
    (folder / "short_lists.yaml").write_text("name: lists\nroute: [" + ",".join(["[1]"] * 1_300_000) + "]\n")
    (folder / "huge.yaml").write_text("name: huge\nroute: [" + ", ".join(["[1, 2, 3, 4, 5, 6, 7, 8]"] * 1_900_000)
                                      + "]\n")
    fence = ", ".join(f"[{i % 1000}, {i // 1000}]" for i in range(1_000_000))
    (folder / "fence_1e6.yaml").write_text(f"name: fence\n{SENSORS}safety:\n  geofence: [{fence}]\n{ROUTE}")
    square = [(0, k) for k in range(2000)] + [(k, 2000) for k in range(2000)] + [(2000, 2000 - k) for k in
                                                                                 range(2000)]
    fence = ", ".join(f"[{n}, {e}]" for n, e in square)
    (folder / "fence_6000.yaml").write_text(f"name: fence\n{SENSORS}safety:\n  geofence: [{fence}]\n{ROUTE}")
    return folder


def test_an_alias_bomb_is_refused_while_parsing(corpus):
    path = corpus / "alias_bomb.yaml"
    assert_refused(run_auv("validate", path), path, "aliases expanded")


def test_ten_thousand_nested_brackets_are_refused_at_the_nesting_limit(corpus):
    path = corpus / "nested.yaml"
    outcome = run_auv("validate", path)
    assert_refused(outcome, path, f"nesting deeper than {limits.MAX_DEPTH} levels")
    assert f"{path}:2:{7 + limits.MAX_DEPTH}:" in outcome.output  # the bracket past the limit (the top is level 1)


def test_a_million_short_lists_are_refused_at_the_list_length_limit(corpus):
    path = corpus / "short_lists.yaml"
    assert_refused(run_auv("validate", path), path, f"more than {limits.MAX_ITEMS:,} entries")


def test_a_file_over_the_size_cap_is_refused_before_it_is_read(corpus):
    path = corpus / "huge.yaml"
    assert path.stat().st_size > limits.MAX_FILE_BYTES
    assert_refused(run_auv("validate", path), path, "are refused")


def test_a_geofence_of_a_million_points_is_refused(corpus):
    path = corpus / "fence_1e6.yaml"
    assert_refused(run_auv("validate", path), path, "are refused")  # 10 MB: over the size cap


def test_a_geofence_of_six_thousand_points_is_refused_by_the_schema(corpus):
    path = corpus / "fence_6000.yaml"
    assert_refused(run_auv("validate", path), path, f"at most {limits.MAX_POLYGON_VERTICES} items")


def test_a_fifo_is_refused_without_blocking(tmp_path):
    fifo = tmp_path / "mission.yaml"
    os.mkfifo(fifo)
    assert_refused(run_auv("validate", fifo), fifo, "FIFO")


@pytest.mark.parametrize("device", ["/dev/zero", "/dev/urandom", "/proc/self/status", "/proc/self/mem"])
def test_devices_and_kernel_files_are_refused(device):
    assert_refused(run_auv("validate", device), device, "system file")


def test_a_folder_is_refused(tmp_path):
    assert_refused(run_auv("validate", tmp_path), tmp_path, "is a folder")


def test_a_binary_file_is_refused_as_not_text(tmp_path):
    path = tmp_path / "mission.yaml"
    path.write_bytes(b"name: x\n\xff\xfe\x00binary")
    assert_refused(run_auv("validate", path), path, "not UTF-8 text")


@pytest.mark.parametrize("document, line", [
    ("name: x\nsensors: !!python/object/apply:os.system {usbl: {sigma: 1}}\n" + ROUTE, 2),
    ("name: x\n" + SENSORS + "route: !!python/object/apply:os.system [{id: go, transit: {to: home}}]\n", 4),
    ("!!python/object/apply:os.system\nname: x\n" + SENSORS + ROUTE, 1),
    ("name: !!python/object/apply:os.system [echo]\n" + SENSORS + ROUTE, 1),
    ("name: x\n" + SENSORS + "route:\n  - !!python/object:__main__.Evil {id: go, transit: {to: home}}\n", 5),
    ("name: x\n" + SENSORS + "route:\n  - id: go\n    transit: {to: !!set {home: null}}\n", 6),
    ("name: x\n" + SENSORS + "seed: !!binary aGVsbG8=\n" + ROUTE, 4),
    ("name: x\n" + SENSORS + "seed: !custom 3\n" + ROUTE, 4),
], ids=["mapping", "sequence", "document", "scalar", "list-item", "set", "binary", "local-tag"])
def test_a_tag_on_any_node_is_refused(tmp_path, document, line):
    path = tmp_path / "mission.yaml"
    path.write_text(document)
    outcome = run_auv("validate", path)
    assert_refused(outcome, path, "is not allowed")
    assert re.search(rf"^{re.escape(str(path))}:{line}:\d+: document refused: the tag", outcome.output, re.M)


def test_a_recursive_alias_is_refused(tmp_path):
    path = tmp_path / "mission.yaml"
    path.write_text("name: x\n" + SENSORS + "route: &r [*r]\n")
    assert_refused(run_auv("validate", path), path, "a node that contains it")


def test_a_world_path_to_a_non_world_file_names_the_path_and_never_quotes_the_file(tmp_path):
    secret = tmp_path / "shadow"
    secret.write_text("root: $6$s3cr3t-hash-line\nSecretKey: hunter2-token\ndaemon: '*'\n")
    path = tmp_path / "mission.yaml"
    path.write_text(f"name: x\nworld: {secret}\n{SENSORS}{ROUTE}")
    outcome = run_auv("validate", path)
    assert_refused(outcome, path, "is not a world file")
    for word in ("s3cr3t", "hunter2", "SecretKey", "daemon"):
        assert word not in outcome.output


@pytest.mark.parametrize("target", ["/dev/zero", "/proc/self/environ", "fifo", "."])
def test_a_world_path_to_a_device_fifo_or_folder_is_refused_at_the_world_key(tmp_path, target):
    if target == "fifo":
        os.mkfifo(tmp_path / "fifo")
    path = tmp_path / "mission.yaml"
    path.write_text(f"name: x\nworld: {target}\n{SENSORS}{ROUTE}")
    outcome = run_auv("validate", path)
    assert_refused(outcome, path, "cannot be used")
    assert f"{path}:2:8:" in outcome.output


def test_a_model_path_to_a_fifo_is_refused_at_the_model_key(tmp_path):
    os.mkfifo(tmp_path / "model.yaml")
    path = tmp_path / "mission.yaml"
    path.write_text(f"name: x\n{SENSORS}objects:\n  - id: o\n    pose: {{north: 0, east: 0, depth: 10}}\n"
                    f"    size: [1, 1, 1]\n    model: model.yaml\n{ROUTE}")
    assert_refused(run_auv("validate", path), path, "FIFO")


def test_a_transit_faster_than_the_vehicle_is_refused_at_its_speed(tiny):
    tiny.write_text(tiny.read_text().replace("speed: 1.0", "speed: 3.0"))
    outcome = run_auv("validate", tiny)
    assert_refused(outcome, tiny, "exceeds vehicle.max_speed 2 m/s")
    assert f"{tiny}:22:" in outcome.output


def test_a_seabed_resolution_of_1e_300_is_refused_in_the_world_file(tiny):
    world = tiny.parent / "tiny_world.yaml"
    world.write_text(world.read_text().replace("resolution: 1.0", "resolution: 1e-300"))
    assert_refused(run_auv("validate", tiny), world, "seabed.resolution")


def test_a_seabed_grid_over_the_cell_limit_is_refused(tiny):
    world = tiny.parent / "tiny_world.yaml"
    world.write_text(world.read_text().replace("resolution: 1.0", "resolution: 0.05"))
    assert_refused(run_auv("validate", tiny), world, "cells is too large")


def test_a_survey_of_a_million_lines_is_refused(tiny):
    tiny.write_text(tiny.read_text().replace("  usbl:", "  mbes: {swath_deg: 1}\n  usbl:") + """\
  - id: mow
    survey: {area: [[-40, -40], [-40, 40], [40, 40], [40, -40]], altitude: 1.0, overlap: 90%}
""")
    assert_refused(run_auv("validate", tiny), tiny, "lines (at most")
