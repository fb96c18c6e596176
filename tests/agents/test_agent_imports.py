"""Agents run onboard: they import neither a plug-in's internals (plug-ins are loaded by entry point and called
through the host) nor the simulator, the plots or the benchmarks."""

from __future__ import annotations

import ast
from pathlib import Path

AGENTS = Path(__file__).resolve().parents[2] / "mission" / "agents"
FORBIDDEN = ("perception_plugins", "mission.sim", "mission.plots", "mission.bench")


def imported_modules(path: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            names.add(node.module)
    return names


def test_agents_import_no_plug_in_internals_simulator_plots_or_benchmarks():
    modules = sorted(AGENTS.rglob("*.py"))
    assert len(modules) > 20
    leaks = {f"{path.relative_to(AGENTS)}: {name}" for path in modules for name in imported_modules(path)
             if name.startswith(FORBIDDEN) or name.endswith("_plots")}
    assert leaks == set()
