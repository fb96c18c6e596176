"""The `auv` commands of the onboard side: `auv run`, `auv vehicles`, `auv score` and `auv sim serve` (a thin shell
over `mission.onboard.run`, `mission.vehicles`, `mission.score` and `mission.sim.serve`; `mission.cli` adds them)."""

from __future__ import annotations

import argparse
import json
import signal
import sys
from pathlib import Path
from typing import Any

from mission.cli_export import add_mcap_option, write_mcap_if_asked
from mission.errors import Diagnostic, MissionError
from mission.interrupt import exit_code


def _run(args: argparse.Namespace) -> int:
    from mission.language import validate_mission_file
    from mission.onboard.run import run_onboard

    mission, diags = validate_mission_file(args.mission)
    if mission is None:
        raise MissionError([d for d in diags if not d.warning])
    for d in diags:
        print(d, file=sys.stderr)
    if mission.faults:
        from mission.faults import faults_diagnostic

        raise MissionError([faults_diagnostic(mission, "`auv run` flies a real vehicle")])
    out = Path(args.out) if args.out else Path("runs") / f"{mission.name}-onboard"
    drivers = sensor_driver_options(mission, args.sensor_driver or [], args.mission)
    print(f"{mission.name}: connecting to {args.vehicle} (up to {args.connect_timeout:g} s)", file=sys.stderr)
    result = run_onboard(mission, args.vehicle, out, connect_timeout=args.connect_timeout, sensor_drivers=drivers,
                         force=args.force)
    m = result.metrics
    state = "completed" if m["completed"] else ("LINK LOST" if m["link_lost"] else
                                                "STOPPED" if m["stopped"] else
                                                "ABORTED: " + (m["abort_reason"] or "") if m["aborted"]
                                                else "not completed")
    print(f"{mission.name}: {state}; {m['mission_time_s']:.0f} s of vehicle time in {m['wall_time_s']:.1f} s, "
          f"{m['distance_m']:.0f} m (estimated), {m['energy_wh']:.0f} Wh")
    for e in m["elements"]:
        extra = f" ({e['reason']})" if e.get("reason") else ""
        print(f"  {e['id']:<24} {e['kind']:<9} {e['status']:<10} {e['duration_s']:8.1f} s{extra}")
    print(f"run folder: {out}")
    write_mcap_if_asked(args, out)
    if m.get("interrupted"):
        return exit_code(getattr(signal.Signals, m["signal"]))
    return 0 if m["completed"] else 1


def sensor_driver_options(mission: Any, options: list[str], args_mission: str = "") -> dict[str, str]:
    """`--sensor-driver` values → sensor name → driver URI (a bare URI applies to every sensor the mission has)."""
    from mission.sensors import SENSOR_NAMES

    drivers: dict[str, str] = {}
    for option in options:
        name, sep, uri = option.partition("=")
        if sep and name in SENSOR_NAMES:
            if getattr(mission.sensors, name) is None:
                raise MissionError([Diagnostic(str(args_mission), 1, 1, f"--sensor-driver {option}: the mission's "
                                               f"`sensors` have no {name}")])
            drivers[name] = uri
        else:
            drivers.update({n: option for n in SENSOR_NAMES if getattr(mission.sensors, n) is not None})
    return drivers


def _vehicles(args: argparse.Namespace) -> int:
    from mission.vehicles import installed_vehicles

    found = installed_vehicles()
    if args.json:
        print(json.dumps(found, indent=2))
    elif not found:
        print("no vehicle adapters installed (entry-point group auv.vehicles)")
    for scheme, target in sorted(found.items()):
        if not args.json:
            print(f"{scheme:<12} {target}")
    return 0


def _score(args: argparse.Namespace) -> int:
    from mission.score import score_run

    m = score_run(args.run, args.truth)
    nav = m["navigation"]
    print(f"{args.run}: scored against {args.truth}: nav error rms {nav['position_error_rms_m']:.2f} m, "
          f"max {nav['position_error_max_m']:.2f} m; {m['distance_m']:.0f} m truly flown; "
          f"{m['seabed_contacts']} seabed contact(s)")
    return 0


# -- `auv sim serve` (the simulator as a MAVLink vehicle) -------------------------------------------------------
def _sim_serve(args: argparse.Namespace) -> int:
    import signal
    import threading

    from mission.language import validate_mission_file
    from mission.sim.serve import serve

    mission, diags = validate_mission_file(args.mission)
    if mission is None:
        raise MissionError([d for d in diags if not d.warning])
    stop, streams_stop = threading.Event(), threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stop.set())
    signal.signal(signal.SIGUSR1, lambda *_: streams_stop.set())  # rehearse a payload failure
    seed = mission.seed if args.seed is None else args.seed
    print(f"{mission.name}: serving the simulated vehicle on {', '.join(args.mavlink)} at {args.speedup:g}x "
          f"(seed {seed})" + (f"; truth in {args.out}" if args.out else ""), flush=True)

    def show(event: dict[str, Any]) -> None:
        fields = " ".join(f"{k}={v}" for k, v in event.items() if k not in ("time", "event"))
        print(f"  t={event['time']:9.1f} s  {event['event']} {fields}", flush=True)

    if args.zenoh:
        print(f"payload streams on Zenoh {', '.join(args.zenoh)} under {args.zenoh_prefix}/", flush=True)
    summary = serve(mission, args.mavlink, seed=seed, speedup=args.speedup, out=args.out, stop_event=stop,
                    on_event=None if args.quiet else show, zenoh=args.zenoh or (), zenoh_prefix=args.zenoh_prefix,
                    streams_stop=streams_stop, force=args.force)
    print(f"stopped: {summary.sim_time:.1f} s of vehicle time in {summary.wall_time:.1f} s "
          f"({summary.steps} steps)", flush=True)
    return 0


def _add_sim_parser(sub: Any) -> None:
    p = sub.add_parser("sim", help="the simulator behind a vehicle protocol")
    ssub = p.add_subparsers(dest="sim_command", required=True)
    p = ssub.add_parser("serve", help="serve the simulated vehicle as an ArduSub autopilot over MAVLink")
    p.add_argument("mission", help="mission YAML file (its world, vehicle, sensors and seed)")
    p.add_argument("--mavlink", action="append", required=True, metavar="ADDRESS",
                   help="pymavlink connection string, e.g. udpout:127.0.0.1:14550 (repeat for more links)")
    p.add_argument("--speedup", type=float, default=1.0, help="vehicle seconds per wall second (default 1)")
    p.add_argument("--seed", type=int, help="random seed (default: the mission's)")
    p.add_argument("--out", help="write the truth here as it goes (mission.yaml, world.yaml, trajectory.csv, "
                   "usbl.csv, autopilot.jsonl)")
    p.add_argument("--force", action="store_true", help="replace an earlier truth folder whole")
    p.add_argument("--zenoh", action="append", metavar="ENDPOINT",
                   help="also publish the payload streams on Zenoh, listening here, e.g. tcp/127.0.0.1:7447 "
                   "(SIGUSR1 stops them, to rehearse a payload failure)")
    p.add_argument("--zenoh-prefix", default="auv/sim", metavar="KEY", help="key prefix (default auv/sim)")
    p.add_argument("-q", "--quiet", action="store_true", help="do not print the autopilot's events")
    p.set_defaults(func=_sim_serve)
# -- end of `auv sim serve` ------------------------------------------------------------------------------------


def add_onboard_commands(sub: Any) -> None:
    """Register the onboard commands on the `auv` parser's sub-parsers."""
    p = sub.add_parser("run", help="fly a mission on a vehicle (onboard executive, the vehicle's clock)")
    p.add_argument("mission", help="mission YAML file")
    p.add_argument("--vehicle", required=True, metavar="URI",
                   help="vehicle adapter and address, e.g. mavlink:udpin:0.0.0.0:14550 (`auv vehicles` lists them)")
    p.add_argument("--out", help="run folder (default: runs/MISSION_NAME-onboard)")
    p.add_argument("--force", action="store_true", help="replace an earlier run's folder whole")
    p.add_argument("--connect-timeout", type=float, default=10.0, metavar="S",
                   help="seconds to wait for the vehicle (default 10)")
    p.add_argument("--sensor-driver", action="append", metavar="[SENSOR=]URI",
                   help="payload stream driver for SENSOR (mbes, stereo, scanner), or for every sensor the mission "
                   "has, overriding the mission's `driver:`; e.g. zenoh:auv/sim?connect=tcp/127.0.0.1:7447")
    add_mcap_option(p)
    p.set_defaults(func=_run)

    p = sub.add_parser("vehicles", help="list installed vehicle adapters (entry-point group auv.vehicles)")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=_vehicles)

    p = sub.add_parser("score", help="score an `auv run` folder against the truth `auv sim serve --out` kept")
    p.add_argument("run", help="run folder written by `auv run`")
    p.add_argument("--truth", required=True, help="folder written by `auv sim serve --out`")
    p.set_defaults(func=_score)
    _add_sim_parser(sub)
