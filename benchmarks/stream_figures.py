"""Payload-stream figures for the README.

    python benchmarks/stream_figures.py latency [--seconds 20] [--rate 10] [--size 1200x900]
    python benchmarks/stream_figures.py speedup MISSION [--speedup 5]

`latency`: a publisher PROCESS sends stereo pairs (two sensor_msgs/Image mono8 + two CameraInfo, CDR) on Zenoh
over TCP loopback at the given rate, stamped with the host's clock; this process receives them with the `zenoh`
sensor driver into an onboard `SensorStream` drained by a 5 Hz control loop, and prints the pairs per second
delivered, the latency from the sensor stamp to the driver (transport and decoding) and to the agent (at the next
control tick), and the frames dropped.

`replay-vo FOLDER`: the `replay` driver plays a KITTI-layout folder at its recorded pace into an onboard
`SensorStream`; `stereo-vo` (`--method`, default adaptive as `auv vo` runs) takes each pair as it is delivered, in
real time; prints the pairs delivered and dropped, the VO time per pair, and how far the poses are from
`auv vo`'s for the same folder.

`photos RUN_DIR TRUTH_DIR MISSION`: scores an onboard inspection's photographs against the truth `auv sim serve
--out` kept, as `auv simulate` scores them (`mission.sim.inspect_metrics`): the true camera error against the
planned viewpoint, and whether the target is in the picture.

`speedup`: flies MISSION with `auv run` (zenoh driver) against `auv sim serve --zenoh --speedup K` and prints each
stream's received / delivered / dropped frames from the run's metrics.json.
"""

from __future__ import annotations

import argparse
import json
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def free_port(kind: int = socket.SOCK_STREAM) -> int:
    with socket.socket(socket.AF_INET, kind) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def publish(port: int, seconds: float, rate: float, width: int, height: int) -> None:
    """The publisher process: stereo pairs at `rate` Hz for `seconds`, stamped with time.time()."""
    from mission.sensors import ros_msgs as ros
    from mission.sensors.zenoh_keys import open_session

    session = open_session(listen=[f"tcp/127.0.0.1:{port}"])
    pubs = {k: session.declare_publisher(f"auv/bench/stereo/{k}") for k in (
        "left/image_raw", "right/image_raw", "left/camera_info", "right/camera_info")}
    rng = np.random.default_rng(0)
    left = rng.integers(0, 255, (height, width), dtype=np.uint8)
    right = np.roll(left, -20, axis=1)
    K = np.array([[1000.0, 0, width / 2], [0, 1000.0, height / 2], [0, 0, 1]])
    time.sleep(1.0)  # the subscriber connects
    start = time.monotonic()
    k = 0
    while time.monotonic() - start < seconds:
        due = start + k / rate
        time.sleep(max(due - time.monotonic(), 0.0))
        t = time.time()
        for side, image in (("left", left), ("right", right)):
            pubs[f"{side}/camera_info"].put(ros.encode(ros.camera_info_msg(t, K, width, height, 0.25,
                                                                           f"stereo_{side}", side == "right")))
            pubs[f"{side}/image_raw"].put(ros.encode(ros.image_msg(t, image, f"stereo_{side}")))
        k += 1
    time.sleep(0.5)
    session.close()


def latency(args: argparse.Namespace) -> None:
    from mission.language.models import Stereo
    from mission.sensors import DriverContext, open_driver
    from mission.sensors.navtrack import NavTrack
    from mission.sensors.streams import SensorStream
    from mission.vehicle import NavState

    width, height = (int(v) for v in args.size.split("x"))
    port = free_port()
    child = subprocess.Popen([sys.executable, __file__, "_publish", str(port), str(args.seconds), str(args.rate),
                              str(width), str(height)], cwd=ROOT)
    transport: list[float] = []

    def opener(uri: str, context: DriverContext):  # type: ignore[no-untyped-def]
        def sink(frame):  # type: ignore[no-untyped-def]
            transport.append(time.time() - frame.time)
            context.sink(frame)

        return open_driver(uri, DriverContext(context.sensor, context.settings, sink))

    stream = SensorStream("stereo", f"zenoh:auv/bench?connect=tcp/127.0.0.1:{port}", Stereo(), 5.0, opener)
    stream.switch(True, None)
    track = NavTrack()
    to_agent: list[float] = []
    first = last = None
    end = time.monotonic() + args.seconds + 3.0
    while time.monotonic() < end:
        now = time.time()
        track.add(NavState(now, 0, 0, 0, 0, 0, None, 1.0, 0.0))
        for frame in stream.collect(track, time.monotonic()):
            delivered = time.time()
            to_agent.append(delivered - frame.time)
            first = first or delivered
            last = delivered
        time.sleep(0.2)
    stream.close()
    child.wait(10)
    n = len(to_agent)
    rate = (n - 1) / (last - first) if n > 1 and first and last else 0.0

    def ms(values: list[float]) -> str:
        v = np.array(values) * 1000.0
        return f"median {np.median(v):.1f} ms, p95 {np.percentile(v, 95):.1f} ms, max {v.max():.1f} ms"

    print(f"stereo {width}x{height} mono8 at {args.rate:g} Hz over Zenoh (TCP loopback, peer to peer), "
          f"{args.seconds:g} s")
    print(f"  pairs delivered to the agents: {n} ({rate:.1f} pairs/s); dropped {stream.stats.dropped}; "
          f"received {stream.stats.received}")
    print(f"  sensor stamp -> driver (transport + CDR decoding): {ms(transport)}")
    print(f"  sensor stamp -> agent (at the next 5 Hz control tick): {ms(to_agent)}")


def replay_vo(args: argparse.Namespace) -> None:
    from mission.language.models import Stereo
    from mission.plugin_api import OdometryRequest
    from mission.sensors.navtrack import NavTrack
    from mission.sensors.streams import SensorStream
    from perception_plugins.vo import estimate_trajectory, read_kitti_sequence
    from perception_plugins.vo.plugin import StereoOdometryPlugin

    plugin = StereoOdometryPlugin()
    plugin.configure({"method": args.method})
    frames = len(read_kitti_sequence(args.folder))
    stream = SensorStream("stereo", f"replay:{args.folder}", Stereo(), 5.0)
    stream.switch(True, None)
    track = NavTrack()
    poses: dict[float, np.ndarray] = {}
    spent: list[float] = []
    first = True
    end = time.monotonic() + frames / 10.0 + 5.0
    delivered = 0
    while time.monotonic() < end and delivered < frames:
        got = stream.collect(track, time.monotonic())
        for frame in got:
            t0 = time.perf_counter()
            result = plugin.process(frame, OdometryRequest(set_origin=first))
            spent.append(time.perf_counter() - t0)
            first = False
            if result.ok and result.T_origin_cam is not None:
                poses[frame.time] = result.T_origin_cam
        delivered += len(got)
        if not got:
            time.sleep(0.005)
    stream.close()
    sequence = read_kitti_sequence(args.folder)
    reference = estimate_trajectory(sequence, method=args.method)
    index = {round(float(t), 6): i for i, t in enumerate(sequence.times)}
    errors = [float(np.linalg.norm(T[:3, 3] - reference[index[round(t, 6)]][:3, 3])) for t, T in poses.items()]
    print(f"replay of {args.folder} ({frames} pairs at its times.txt pace) into stereo-vo ({args.method}), "
          "in real time")
    print(f"  pairs delivered {stream.stats.delivered}, dropped {stream.stats.dropped}; VO per pair: median "
          f"{1000 * np.median(spent):.0f} ms, max {1000 * max(spent):.0f} ms")
    print(f"  {len(poses)} VO positions; largest distance from auv vo's pose of the same frame: "
          f"{max(errors):.4f} m")


def speedup(args: argparse.Namespace) -> None:
    auv = [sys.executable, "-m", "mission"]
    udp, tcp = free_port(socket.SOCK_DGRAM), free_port()
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "run"
        server = subprocess.Popen([*auv, "sim", "serve", args.mission, "--mavlink", f"udpout:127.0.0.1:{udp}",
                                   "--speedup", str(args.speedup), "--zenoh", f"tcp/127.0.0.1:{tcp}", "-q"],
                                  cwd=ROOT, stdout=subprocess.DEVNULL)
        try:
            subprocess.run([*auv, "run", args.mission, "--vehicle", f"mavlink:udpin:127.0.0.1:{udp}",
                            "--sensor-driver", f"zenoh:auv/sim?connect=tcp/127.0.0.1:{tcp}", "--out", str(out)],
                           cwd=ROOT, check=False)
        finally:
            server.terminate()
            server.wait(20)
        metrics = json.loads((out / "metrics.json").read_text())
    print(f"{args.mission} at --speedup {args.speedup:g}: completed {metrics['completed']}, "
          f"{metrics['mission_time_s']:.0f} s of vehicle time in {metrics['wall_time_s']:.0f} s")
    for e in metrics["elements"]:
        if e.get("coverage_percent") is not None:
            found = ", ".join(f"({d['north']:.2f}, {d['east']:.2f})" for d in e.get("detections", []))
            print(f"  {e['id']}: coverage {e['coverage_percent']:.2f} %, {e['pings']} pings, detections {found}")
    for name, s in metrics.get("sensors", {}).items():
        print(f"  {name:<8} received {s['received']:>6}  delivered {s['delivered']:>6}  dropped {s['dropped']:>4}  "
              f"stale {s['stale']:>3}  ignored (off) {s['ignored_while_off']:>4}  lost {s['lost_events']}  "
              f"queue latency median {s['queue_latency_median_s']} s")


def photos(args: argparse.Namespace) -> None:
    import csv

    from mission.agents.report import Photo
    from mission.frames import camera_pose
    from mission.language.loader import load_mission, load_world
    from mission.sim.inspect_metrics import _photo_truth
    from mission.world.scene import build_scene

    mission = load_mission(args.mission)
    assert mission.world is not None and mission.sensors.stereo is not None
    scene = build_scene(load_world(mission.world))
    rows = list(csv.DictReader(open(Path(args.truth) / "trajectory.csv", encoding="utf-8")))
    times = np.array([float(r["time"]) for r in rows])
    metrics = json.loads((Path(args.run) / "metrics.json").read_text())
    stereo = mission.sensors.stereo
    for item in (e for e in metrics["elements"] if e["kind"] == "inspect"):
        truth = next(o for o in scene.objects if o.database == item["object"])
        at = {t.id: np.asarray(t.at, float) for t in mission.object(item["object"]).targets}
        shots: dict[str, list[dict[str, object]]] = {}
        for p in item["photos"]:
            r = rows[int(np.argmin(abs(times - p["time"])))]
            T_world_cam = camera_pose(float(r["north"]), float(r["east"]), float(r["depth"]), float(r["heading"]),
                                      baseline=stereo.baseline)
            photo = Photo(p["target"], p["index"], p["time"], p["file"], p["viewpoint_object"], p["T_object_cam_est"],
                          p["camera_error_est_m"], p["altitude_limited"], p["odometry_path_m"])
            shots.setdefault(p["target"], []).append(_photo_truth(photo, T_world_cam, truth.T_world_object,
                                                                  at[p["target"]], stereo))
        print(f"{item['id']}: {len(item['photos'])} photos of {len(shots)} targets ({len(at)} planned)")
        for tid, results in shots.items():
            worst = max(float(str(x["camera_error_m"])) for x in results)
            print(f"  {tid:<16} {len(results)} photos; true camera error max {worst:.3f} m; target in every photo: "
                  f"{all(bool(x['target_in_image']) for x in results)}")


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "_publish":
        port, seconds, rate, width, height = sys.argv[2:7]
        publish(int(port), float(seconds), float(rate), int(width), int(height))
        return
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="what", required=True)
    p = sub.add_parser("latency")
    p.add_argument("--seconds", type=float, default=20.0)
    p.add_argument("--rate", type=float, default=10.0)
    p.add_argument("--size", default="1200x900")
    p.set_defaults(func=latency)
    p = sub.add_parser("replay-vo")
    p.add_argument("folder")
    p.add_argument("--method", default="adaptive", help="VO method (default adaptive, `auv vo`'s)")
    p.set_defaults(func=replay_vo)
    p = sub.add_parser("photos")
    p.add_argument("run")
    p.add_argument("truth")
    p.add_argument("mission")
    p.set_defaults(func=photos)
    p = sub.add_parser("speedup")
    p.add_argument("mission")
    p.add_argument("--speedup", type=float, default=5.0)
    p.set_defaults(func=speedup)
    args = parser.parse_args()
    args.func(args)


if __name__ == "__main__":
    main()
