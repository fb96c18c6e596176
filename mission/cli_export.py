"""`auv export`: a thin shell over `mission.export.export` (and `mission.export.mavlink_plan.upload_mission` for
`--upload`), and the `--mcap` option of the commands that write run folders; `mission.cli` adds them."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any


def _export(args: argparse.Namespace) -> int:
    from mission.export import export

    result = export(args.source, args.format, args.out)
    print(f"{args.source}: {result.count} {result.what} written to {result.out} ({result.format})")
    if args.upload:
        if args.format != "mavlink":
            from mission.errors import AuvError

            raise AuvError("--upload sends a MAVLink mission: it needs --format mavlink")
        from mission.export.mavlink_plan import read_wpl, upload_mission

        items = read_wpl(result.out)
        upload_mission(items, args.upload, timeout=args.timeout)
        print(f"{len(items)} mission items uploaded to {args.upload}")
    return 0


def add_mcap_option(parser: argparse.ArgumentParser) -> None:
    """`--mcap` for the commands that write a run folder (`auv simulate`, `auv run`)."""
    parser.add_argument("--mcap", action="store_true", help="also write the run folder as DIR/run.mcap (ROS 2 "
                        "messages for Foxglove; needs the [interop] extra)")


def write_mcap_if_asked(args: argparse.Namespace, run_dir: Path) -> None:
    """After a run: write `run_dir/run.mcap` when `--mcap` was given."""
    if getattr(args, "mcap", False):
        from mission.mcap_log import write_mcap

        print(f"MCAP log: {write_mcap(run_dir)} messages in {run_dir / 'run.mcap'}")


def add_export_command(sub: Any) -> None:
    """Register `auv export` on the `auv` parser's sub-parsers."""
    from mission.export import FORMATS

    p = sub.add_parser("export", help="export a mission or a run folder as GeoJSON, KML, a MAVLink mission, an IMC "
                                      "plan or an MCAP log")
    p.add_argument("source", help="mission YAML file, or a run folder (`auv simulate --out`, `auv run --out`)")
    p.add_argument("--format", required=True, choices=FORMATS)
    p.add_argument("--out", help="file to write (default: beside the mission, or inside the run folder)")
    p.add_argument("--upload", metavar="ADDRESS", help="with --format mavlink: also send the mission to this "
                   "pymavlink address with the mission protocol (e.g. udpout:127.0.0.1:14550)")
    p.add_argument("--timeout", type=float, default=5.0, help="seconds to wait for the vehicle's answers (default 5)")
    p.set_defaults(func=_export)
