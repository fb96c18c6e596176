"""The onboard install: `auv validate`, `auv run` and what they load work without the [sim] and [plots] extras."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

# Makes mujoco and matplotlib impossible to import, as in a bare `pip install auv-mission`.
BLOCK = """
import sys, importlib.abc
class Block(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target=None):
        if name.split('.')[0] in ('mujoco', 'matplotlib'):
            raise ModuleNotFoundError(f"No module named {name!r}")
sys.meta_path.insert(0, Block())
"""


def _run(code: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-c", BLOCK + code], cwd=ROOT, capture_output=True, text=True,
                          timeout=120)


def test_the_executive_agents_and_vehicle_adapters_load_without_the_simulator_or_plots():
    done = _run("import mission.executive, mission.agents, mission.onboard.run, mission.vehicles, mission.score\n"
                "from importlib.metadata import entry_points\n"
                "for ep in entry_points(group='auv.vehicles'): ep.load()\n"
                "for ep in entry_points(group='auv.perception'): ep.load()\n"
                "bad = [m for m in sys.modules if m.split('.')[0] in ('mujoco', 'matplotlib')]\n"
                "assert not bad, bad\nprint('ok')")
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "ok"


def test_validate_and_run_help_work_without_the_extras():
    cli = "from mission.cli import main\nraise SystemExit(main(sys.argv[1:]))"
    validate = subprocess.run([sys.executable, "-c", BLOCK + cli, "validate", "missions/field_transit.yaml",
                               "missions/sps_field_inspection.yaml"], cwd=ROOT, capture_output=True, text=True,
                              timeout=120)
    assert validate.returncode == 0, validate.stderr
    assert validate.stdout.count(": ok") == 2
    helped = subprocess.run([sys.executable, "-c", BLOCK + cli, "run", "--help"], cwd=ROOT, capture_output=True,
                            text=True, timeout=120)
    assert helped.returncode == 0 and "--vehicle" in helped.stdout


def test_simulate_without_the_simulator_extra_says_which_extra_to_install():
    cli = "from mission.cli import main\nraise SystemExit(main(sys.argv[1:]))"
    done = subprocess.run([sys.executable, "-c", BLOCK + cli, "simulate", "missions/field_transit.yaml"], cwd=ROOT,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 1
    assert "auv-mission[sim]" in done.stderr and "Traceback" not in done.stderr
