"""Benchmarks behind `auv bench NAME [--quick]`: each runs its anchors and ours side by side in one process and
writes `benchmarks/results/NAME.json` (`NAME.quick.json` with `--quick`, beside the full results and never over
them) with `name`, `quick`, `machine`, `timestamp`, `results` and `checks`
(one entry per goal the issue states: `{"value", "target", "pass"}`), computed from this run's measurements.
"""

from __future__ import annotations

import importlib
import json
import os
import platform
import sys
from collections.abc import Callable
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from mission.errors import AuvError

REPO = Path(__file__).resolve().parents[2]
BENCHMARKS: dict[str, str] = {
    "simspeed": "mission.bench.simspeed",
    "sonar": "mission.bench.sonar",
    "mapping": "mission.bench.mapping",
    "coverage": "mission.bench.coverage",
    "stereo": "mission.bench.stereo",
    "referencing": "mission.bench.referencing",
    "referencing-sets": "mission.bench.referencing_sets",
    "ordering": "mission.bench.ordering",
    "rrt": "mission.bench.rrt",
    "nbv": "mission.bench.nbv",
    "explore-shapes": "mission.bench.explore_shapes",
    "multiview": "mission.bench.multiview",
    "vo": "mission.bench.vo",
    "photo-survey": "mission.bench.photo_survey",
    "reconstruction": "mission.bench.reconstruction",
}

BenchFn = Callable[[bool], tuple[dict[str, Any], dict[str, dict[str, Any]]]]


def check(value: float, target: str) -> dict[str, Any]:
    """A check entry: `target` is a comparison such as '>= 720' or '<= 5'."""
    op, bound = target.split()
    ok = value >= float(bound) if op == ">=" else value <= float(bound)
    return {"value": value, "target": target, "pass": bool(ok)}


def machine() -> dict[str, Any]:
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {"cpu": cpu, "cores": os.cpu_count(), "python": sys.version.split()[0], "platform": platform.platform()}


def results_path(name: str, quick: bool, out_dir: Path | None = None) -> Path:
    """Where a benchmark's record goes: `NAME.json` for a full run, `NAME.quick.json` for a quick one.

    >>> results_path("vo", True, Path("r")).as_posix(), results_path("vo", False, Path("r")).as_posix()
    ('r/vo.quick.json', 'r/vo.json')
    """
    return (out_dir or REPO / "benchmarks" / "results") / f"{name}{'.quick' if quick else ''}.json"


def run_benchmark(name: str, quick: bool = False, out_dir: Path | None = None) -> dict[str, Any]:
    """Run one benchmark and write its JSON (`results_path`); returns the record."""
    if name not in BENCHMARKS:
        raise AuvError(f"unknown benchmark '{name}' (available: {', '.join(sorted(BENCHMARKS))})")
    module = importlib.import_module(BENCHMARKS[name])
    results, checks = module.run(quick)
    record = {"name": name, "quick": quick, "machine": machine(),
              "timestamp": datetime.now(UTC).isoformat(timespec="seconds"),
              "results": results, "checks": checks}
    path = results_path(name, quick, out_dir)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(record, indent=2) + "\n", encoding="utf-8")
    return record
