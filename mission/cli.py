"""The `auv` command: a thin shell over the public functions. Known errors become one-line messages and exit
codes (0 ok, 1 invalid input or failed run, 2 usage); a traceback means a bug in auv-mission.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path

from mission.errors import AuvError, MissionError


def _validate(args: argparse.Namespace) -> int:
    from mission.language import validate_mission_file

    status = 0
    for path in args.missions:
        _, diags = validate_mission_file(path)
        for d in diags:
            print(d)
        if diags:
            status = 1
            print(f"{path}: {len(diags)} problem(s)", file=sys.stderr)
        elif not args.quiet:
            print(f"{path}: ok")
    return status


def _schema(args: argparse.Namespace) -> int:
    from mission.language.loader import mission_schema_json

    text = mission_schema_json()
    if args.output:
        Path(args.output).write_text(text + "\n", encoding="utf-8")
    else:
        print(text)
    return 0


def _simulate(args: argparse.Namespace) -> int:
    from mission.language import load_mission
    from mission.sim.run import check_supported, simulate

    mission = load_mission(args.mission)
    check_supported(mission)
    out = Path(args.out) if args.out else Path("runs") / mission.name
    result = simulate(mission, seed=args.seed, out=out, plots=not args.no_plots, progress=not args.quiet)
    m = result.metrics
    state = "completed" if m["completed"] else ("ABORTED: " + (m["abort_reason"] or "") if m["aborted"]
                                                 else "not completed")
    print(f"{mission.name}: {state}; {m['mission_time_s']:.0f} s mission time in {m['wall_time_s']:.2f} s "
          f"({m['realtime_factor']}x real time), {m['distance_m']:.0f} m, {m['energy_wh']:.0f} Wh, "
          f"nav error rms {m['navigation']['position_error_rms_m']:.2f} m")
    for e in m["elements"]:
        extra = f" ({e['reason']})" if e.get("reason") else ""
        print(f"  {e['id']:<24} {e['kind']:<9} {e['status']:<10} {e['duration_s']:8.1f} s{extra}")
    print(f"run folder: {out}")
    return 0 if m["completed"] else 1


def _plot(args: argparse.Namespace) -> int:
    from mission.plots import plot_run

    for path in plot_run(Path(args.run)):
        print(path)
    return 0


def _plugins(args: argparse.Namespace) -> int:
    from mission.plugins import installed_plugins

    found = installed_plugins()
    if args.json:
        print(json.dumps({name: ep.value for name, ep in sorted(found.items())}, indent=2))
    elif not found:
        print("no perception plug-ins installed (entry-point group auv.perception)")
    for name, ep in sorted(found.items()):
        if not args.json:
            print(f"{name:<24} {ep.value}")
    return 0


def _bench(args: argparse.Namespace) -> int:
    from mission.bench import BENCHMARKS, run_benchmark

    if args.list or not args.name:
        print("\n".join(sorted(BENCHMARKS)))
        return 0
    record = run_benchmark(args.name, quick=args.quick, out_dir=Path(args.out) if args.out else None)
    print(json.dumps(record["results"], indent=2))
    failed = [k for k, c in record["checks"].items() if not c["pass"]]
    for key, c in record["checks"].items():
        print(f"{'PASS' if c['pass'] else 'FAIL'}  {key}: {c['value']} (target {c['target']})")
    return 1 if failed else 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="auv", description="Plan, simulate and execute AUV inspection missions.")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("validate", help="check missions and report every problem as FILE:LINE:COL")
    p.add_argument("missions", nargs="+", help="mission YAML files")
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing for valid missions")
    p.set_defaults(func=_validate)

    p = sub.add_parser("schema", help="print the JSON Schema of the mission language")
    p.add_argument("-o", "--output", help="write to this file instead of standard output")
    p.set_defaults(func=_schema)

    p = sub.add_parser("simulate", help="simulate a mission and write a run folder")
    p.add_argument("mission", help="mission YAML file")
    p.add_argument("--out", help="run folder (default: runs/MISSION_NAME)")
    p.add_argument("--seed", type=int, help="random seed (default: the mission's)")
    p.add_argument("--no-plots", action="store_true", help="skip the figures")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_simulate)

    p = sub.add_parser("plot", help="redraw a run folder's figures from its files")
    p.add_argument("run", help="run folder written by `auv simulate`")
    p.set_defaults(func=_plot)

    p = sub.add_parser("bench", help="run a benchmark and write benchmarks/results/NAME.json")
    p.add_argument("name", nargs="?", help="benchmark name (see --list)")
    p.add_argument("--quick", action="store_true", help="a shorter run (under 60 s) that still fills every check")
    p.add_argument("--list", action="store_true", help="list the benchmarks")
    p.add_argument("--out", help="results folder (default: benchmarks/results)")
    p.set_defaults(func=_bench)

    p = sub.add_parser("plugins", help="list installed perception plug-ins")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=_plugins)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return int(args.func(args))
    except MissionError as exc:
        for d in exc.diagnostics:
            print(d, file=sys.stderr)
        return 1
    except AuvError as exc:
        print(f"auv: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("auv: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
