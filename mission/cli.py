"""The `auv` command: a thin shell over the public functions. Known errors become one-line messages and exit
codes (0 ok, 1 invalid input or failed run, 2 usage, 130/143 a run stopped by SIGINT/SIGTERM, 141 a closed
output pipe); a traceback means a bug in auv-mission.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from mission.cli_export import add_export_command, add_mcap_option, write_mcap_if_asked
from mission.cli_onboard import add_onboard_commands
from mission.cli_plan import add_plan_commands
from mission.cli_reconstruct import add_reconstruct_command
from mission.cli_report import add_report_command
from mission.errors import AuvError, MissionError
from mission.extras import has, require
from mission.interrupt import Interrupted, exit_code


def _validate(args: argparse.Namespace) -> int:
    from mission.language import validate_mission_file

    status = 0
    for path in args.missions:
        mission, diags = validate_mission_file(path)
        for d in diags:
            print(d)
        if mission is not None and not args.quiet:
            from mission.language.detectability import detectability_notes

            for note in detectability_notes(path, mission):
                print(note)
        if args.estimate and mission is not None:
            from mission.cli_plan import print_estimate

            print_estimate(mission, args.json)
        errors = sum(1 for d in diags if not d.warning)
        warnings = len(diags) - errors
        if errors:
            status = 1
            print(f"{path}: {errors} problem(s)" + (f", {warnings} warning(s)" if warnings else ""), file=sys.stderr)
        elif warnings:
            print(f"{path}: ok, {warnings} warning(s)")
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
    require("mujoco", "the simulator (`auv simulate`)")
    from mission.language import validate_mission_file
    from mission.sim.run import check_supported, simulate

    mission, diags = validate_mission_file(args.mission)
    if mission is None:
        raise MissionError([d for d in diags if not d.warning])
    for d in diags:  # warnings: legal, but probably not meant
        print(d, file=sys.stderr)
    check_supported(mission)
    if not args.no_plots and not has("matplotlib"):
        print("auv: matplotlib is not installed, so no figures (pip install 'auv-mission[plots]')", file=sys.stderr)
        args.no_plots = True
    if args.seeds is not None:
        return _campaign(args, mission.name)
    out = Path(args.out) if args.out else Path("runs") / mission.name
    result = simulate(mission, seed=args.seed, out=out, plots=not args.no_plots, progress=not args.quiet,
                      record_stereo=args.record_stereo, plugin_latency_s=args.plugin_latency, force=args.force,
                      signals=True)
    m = result.metrics
    state = "completed" if m["completed"] else ("INTERRUPTED" if m.get("interrupted") else
                                                "ABORTED: " + (m["abort_reason"] or "") if m["aborted"]
                                                else "not completed")
    print(f"{mission.name}: {state}; {m['mission_time_s']:.0f} s mission time in {m['wall_time_s']:.2f} s "
          f"({m['realtime_factor']}x real time), {m['distance_m']:.0f} m, {m['energy_wh']:.0f} Wh, "
          f"nav error rms {m['navigation']['position_error_rms_m']:.2f} m")
    for e in m["elements"]:
        extra = f" ({e['reason']})" if e.get("reason") else ""
        print(f"  {e['id']:<24} {e['kind']:<9} {e['status']:<10} {e['duration_s']:8.1f} s{extra}")
    print(f"run folder: {out}")
    if args.record_stereo:
        pairs = len(result.vehicle.log.frames)
        print(f"stereo stream: {pairs} pair(s) in {out / 'stereo'} (KITTI layout; `auv vo {out / 'stereo'}`)")
    write_mcap_if_asked(args, out)
    if result.signal is not None:
        return exit_code(result.signal)
    return 0 if m["completed"] else 1


def _latency(text: str) -> float | None:
    if text == "measured":
        return None
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is neither a number of seconds nor 'measured'") from None
    if not 0.0 <= value <= 60.0:
        raise argparse.ArgumentTypeError(f"{value:g} s is outside 0-60 s")
    return value


def _campaign(args: argparse.Namespace, name: str) -> int:
    from mission.sim.campaign import parse_seeds, run_campaign

    if args.seed is not None or args.record_stereo:
        raise AuvError("--seeds runs many seeded runs: it does not combine with --seed or --record-stereo")
    seeds = parse_seeds(args.seeds)
    out = Path(args.out) if args.out else Path("runs") / f"{name}-seeds"
    where = ("on Dask at " + args.dask if args.dask else "on a local Dask cluster") if args.dask is not None \
        else f"{args.jobs} at a time"
    print(f"{name}: {len(seeds)} seeded run(s), {where}, into {out}/seed-N/")

    def line(row: dict[str, Any]) -> None:
        if "error" in row:
            print(f"  seed {row['seed']:>5}  CRASHED  {row['error']}", flush=True)
            return
        state = "completed" if row["completed"] else ("ABORTED" if row["aborted"] else "not completed")
        failed = [i for i, e in row["elements"].items() if e["status"] != "succeeded"]
        print(f"  seed {row['seed']:>5}  {state:<13} {row['mission_time_s']:7.0f} s  wall {row['wall_time_s']:6.0f} s"
              + (f"  failed: {', '.join(failed)}" if failed else ""), flush=True)

    report = run_campaign(args.mission, seeds, out, jobs=args.jobs, plots=not args.no_plots, on_run=line,
                          plugin_latency_s=args.plugin_latency, dask=args.dask, force=args.force)
    s = report["summary"]
    print(f"completed {s['completed']}/{s['runs']} ({s['completed_percent']:g} %), aborted {s['aborted']}, "
          f"crashed {s['crashed']}, safety violations {s['safety_violations']}")
    for ident, e in s["elements"].items():
        worst = ", ".join(f"{k[6:]} {v}" for k, v in e.items() if k.startswith("worst_"))
        tail = f"; worst {worst}" if worst else ""
        print(f"  {ident:<24} {e['kind']:<9} succeeded {e['succeeded']}/{e['runs']}{tail}")
    print(f"campaign: {out / 'campaign.json'}")
    return 0 if s["completed"] == s["runs"] else 1


def _plot(args: argparse.Namespace) -> int:
    require("matplotlib", "`auv plot`")
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


def _eval_traj(args: argparse.Namespace) -> int:
    from mission.trajectory_eval import evaluate, read_trajectory, rpe_table, summary_text

    errors = evaluate(read_trajectory(args.ground_truth), read_trajectory(args.estimate), delta=args.delta)
    if args.json:
        print(json.dumps({"ground_truth": args.ground_truth, "estimate": args.estimate, **errors.as_dict()}))
    else:
        print(rpe_table(errors))
        print(summary_text(errors))
    return 0


def _vo(args: argparse.Namespace) -> int:
    import time

    from tqdm import tqdm

    from mission.trajectory_eval import evaluate, summary_text, write_trajectory

    try:
        from perception_plugins import vo
    except ImportError as exc:
        raise AuvError(f"the visual-odometry package is not available: {exc}") from exc
    try:
        sequence = vo.read_kitti_sequence(args.sequence)
        options: dict[str, Any] = {} if args.method is None else {"method": args.method}
        if args.prefilter is not None:
            options["prefilter_px"] = args.prefilter
        with tqdm(total=len(sequence), unit="frame", desc=f"vo {args.method or ''}".strip(), leave=False,
                  mininterval=0.5, disable=args.quiet, file=sys.stderr) as bar:

            def progress(index: int) -> None:  # called after frame `index` (0-based)
                bar.update(max(index + 1 - bar.n, 0))

            wall0 = time.perf_counter()
            poses = vo.estimate_trajectory(sequence, progress=progress, **options)
            wall = time.perf_counter() - wall0
    except vo.VoError as exc:
        raise AuvError(str(exc)) from exc
    write_trajectory(args.out, poses, sequence.times, fmt=args.format)
    print(f"{args.out}: {len(poses)} poses ({args.format}) from {args.sequence} in {wall:.1f} s "
          f"({len(poses) / max(wall, 1e-9):.1f} frames/s)")
    if sequence.gt_poses is not None:
        print(summary_text(evaluate(sequence.gt_poses, poses)))
    return 0


def _model_build(args: argparse.Namespace) -> int:
    from mission.model_build import build_from_run

    views = [int(v) for v in args.views.split(",")] if args.views else None
    report = build_from_run(args.run, args.object, views, args.edits, args.out, args.extend)
    print(f"{report.path}: {args.object} from views {', '.join(report.views)}; full model "
          f"{report.full['points']} points, {report.full['lines']} lines, {report.full['corners']} corners")
    print(f"  object frame in the database frame: {report.database_tie}")
    for row in report.table:
        print(f"  view {row['view']}: {row['points']} points, {row['lines']} lines, {row['corners']} corners")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="auv", description="Plan, simulate and execute AUV inspection missions.")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("validate", help="check missions and report every problem as FILE:LINE:COL")
    p.add_argument("missions", nargs="+", help="mission YAML files")
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing for valid missions")
    p.add_argument("--estimate", action="store_true",
                   help="also print each valid mission's distance, duration, energy and coverage estimate")
    p.add_argument("--json", action="store_true", help="with --estimate, the estimate as JSON")
    p.set_defaults(func=_validate)

    p = sub.add_parser("schema", help="print the JSON Schema of the mission language")
    p.add_argument("-o", "--output", help="write to this file instead of standard output")
    p.set_defaults(func=_schema)

    p = sub.add_parser("simulate", help="simulate a mission and write a run folder")
    p.add_argument("mission", help="mission YAML file")
    p.add_argument("--out", help="run folder (default: runs/MISSION_NAME)")
    p.add_argument("--seed", type=int, help="random seed (default: the mission's)")
    p.add_argument("--seeds", metavar="LIST", help="many seeded runs, e.g. 1-20 or 1,5,9: OUT/seed-N/ each and "
                   "OUT/campaign.json with the completion rate and the worst figures (default OUT runs/NAME-seeds)")
    p.add_argument("--jobs", type=int, default=1, help="with --seeds, runs at a time (processes; default 1)")
    p.add_argument("--force", action="store_true", help="replace an earlier run's (or campaign's) folder whole")
    p.add_argument("--dask", nargs="?", const="", default=None, metavar="SCHEDULER_ADDRESS",
                   help="with --seeds, run on Dask: a local cluster of --jobs workers, or the scheduler at the "
                   "address (workers anywhere; see the README on shared run folders)")
    p.add_argument("--no-plots", action="store_true", help="skip the figures")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.add_argument("--record-stereo", action="store_true",
                   help="write the stereo stream and true poses to DIR/stereo/ (KITTI odometry layout)")
    p.add_argument("--plugin-latency", type=_latency, default=0.1, metavar="S|measured",
                   help="each perception plug-in call's latency charged to the simulated clock (default 0.1 s: "
                   "runs repeat exactly for a seed); 'measured': the call's CPU time, so the run depends on the "
                   "machine")
    add_mcap_option(p)
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

    p = sub.add_parser("eval-traj", help="trajectory errors of an estimate: ATE, RPE, end-point drift")
    p.add_argument("ground_truth", help="ground-truth trajectory (KITTI or TUM file)")
    p.add_argument("estimate", help="estimated trajectory (KITTI or TUM file)")
    p.add_argument("--delta", type=int, default=1, help="RPE over this many frames (default 1)")
    p.add_argument("--json", action="store_true", help="print the metrics as JSON")
    p.set_defaults(func=_eval_traj)

    p = sub.add_parser("vo", help="stereo visual odometry over a KITTI-layout sequence")
    p.add_argument("sequence", help="folder with image_0/, image_1/, calib.txt, times.txt (poses.txt optional)")
    p.add_argument("--out", required=True, help="trajectory file to write")
    p.add_argument("--format", choices=("kitti", "tum"), default="kitti", help="trajectory format (default kitti)")
    p.add_argument("--method", choices=("classic", "klt", "adaptive", "network"),
                   help="VO scheme (default: the VO package's)")
    p.add_argument("--prefilter", type=float, metavar="PX",
                   help="Gaussian low-pass σ (px) on the images (default 0.7; 0 turns it off)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_vo)

    p = sub.add_parser("model", help="multi-view object models (seed 000 §3.1)")
    msub = p.add_subparsers(dest="model_command", required=True)
    p = msub.add_parser("build", help="build (or extend) an object's model from a run folder's stereo recording")
    p.add_argument("run", help="run folder written by `auv simulate MISSION --record-stereo`")
    p.add_argument("--object", required=True, help="object id in the run's mission database")
    p.add_argument("--views", help="frame indices to use, comma-separated (default: chosen by proximity)")
    p.add_argument("--edits", help="operator edits (YAML: base segment, edges and points picked in the images)")
    p.add_argument("--out", help="model file (default: RUN/models/OBJECT.yaml)")
    p.add_argument("--extend", help="extend this existing model with the run's views instead")
    p.set_defaults(func=_model_build)
    add_onboard_commands(sub)
    add_plan_commands(sub)
    add_report_command(sub)
    add_reconstruct_command(sub)
    add_export_command(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return int(args.func(args))
    except MissionError as exc:
        for d in exc.diagnostics:
            print(d, file=sys.stderr)
        return 1
    except Interrupted as exc:
        print(f"auv: {exc}", file=sys.stderr)
        return exc.exit_code
    except AuvError as exc:
        print(f"auv: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("auv: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # the reader went away (`auv … | head`): no traceback, and nothing more to print
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 141


if __name__ == "__main__":
    sys.exit(main())
