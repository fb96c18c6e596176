"""Figures of a run folder: `simulate(..., plots=True)` draws them, `auv plot DIR` redraws them, and a folder with
no world, no USBL fixes or gaps in the altimeter still plots."""

from __future__ import annotations

import csv
import json
import shutil
from pathlib import Path

import pytest
import yaml

from mission import load_mission, simulate
from mission.cli import main
from mission.plots import plot_run

WORLD = Path(__file__).resolve().parents[2] / "worlds" / "sps_field.yaml"
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
FIGURES = ("map.png", "profile.png", "navigation.png")
MISSION = """\
name: plot-check
world: {world}
sensors:
  usbl: {{sigma: 1.5, rate_hz: 0.5}}
safety:
  geofence: [[-60, -60], [-60, 460], [360, 460], [360, -60]]
objects:
  - id: manifold-1
    pose: {{north: 150, east: 200, depth: 58, heading: 30}}
    size: [8, 5, 2.5]
route:
  - id: out
    transit: {{to: {{north: 80, east: 40}}, depth: 20}}
  - id: back
    transit: {{to: home, depth: 0, navigation: dead-reckoning}}
"""


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    tmp = tmp_path_factory.mktemp("plots")
    path = tmp / "plot-check.yaml"
    path.write_text(MISSION.format(world=WORLD.resolve()), encoding="utf-8")
    simulate(load_mission(path), out=tmp / "run", plots=True)
    return tmp / "run"


def _copy(run: Path, dest: Path) -> Path:
    shutil.copytree(run, dest)
    return dest


def _assert_figures(paths: list[Path], where: Path) -> None:
    assert sorted(p.name for p in paths) == sorted(FIGURES)
    for name in FIGURES:
        png = where / name
        assert png.is_file(), name
        assert png.read_bytes()[:8] == PNG_SIGNATURE, name
        assert png.stat().st_size > 20_000, f"{name} is suspiciously small"


def test_simulate_draws_the_figures(run_folder: Path) -> None:
    plots = run_folder / "plots"
    _assert_figures(sorted(plots.glob("*.png")), plots)


def test_cli_plot_redraws_the_figures(run_folder: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    run = _copy(run_folder, tmp_path / "run")
    shutil.rmtree(run / "plots")
    assert main(["plot", str(run)]) == 0
    printed = [Path(line) for line in capsys.readouterr().out.splitlines()]
    _assert_figures(printed, run / "plots")


def test_cli_plot_of_a_missing_folder_is_an_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["plot", str(tmp_path / "nope")]) == 1
    err = capsys.readouterr().err
    assert err.startswith("auv: ") and "nope" in err


def test_plots_without_world_fixes_or_altimeter(run_folder: Path, tmp_path: Path) -> None:
    run = _copy(run_folder, tmp_path / "run")
    shutil.rmtree(run / "plots")
    mission = yaml.safe_load((run / "mission.yaml").read_text(encoding="utf-8"))
    mission["world"] = None
    (run / "mission.yaml").write_text(yaml.safe_dump(mission, sort_keys=False), encoding="utf-8")
    (run / "world.yaml").unlink()
    (run / "usbl.csv").write_text("time,north,east,used,accepted\n", encoding="utf-8")
    with (run / "trajectory.csv").open(newline="", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    k = rows[0].index("altitude_est")
    for row in rows[1:]:
        row[k] = ""
    with (run / "trajectory.csv").open("w", newline="", encoding="utf-8") as f:
        csv.writer(f).writerows(rows)
    violation = {"time": 30.0, "event": "safety_violation", "monitor": "geofence", "message": "outside",
                 "element": "out", "north": 40.0, "east": 20.0, "depth": 15.0}
    with (run / "events.jsonl").open("a", encoding="utf-8") as f:
        f.write(json.dumps(violation) + "\n")

    out = tmp_path / "figures"
    paths = plot_run(run, out_dir=out)
    assert all(p.parent == out for p in paths)
    assert not (run / "plots").exists()
    _assert_figures(paths, out)
