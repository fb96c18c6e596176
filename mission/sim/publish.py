"""`auv sim serve --zenoh ENDPOINT`: the simulated payload streams on Zenoh, as a ROS 2 vehicle would publish them
(`mission.sensors.zenoh_keys` lists the keys, `mission.sensors.ros_msgs` the message shapes).

The multibeam, scanner and stereo camera are the `SimulatedVehicle`'s own: cast or rendered from the TRUE pose
at the vehicle's clock, stamped with it. A sensor runs while a driver asks for it (`PREFIX/SENSOR/request`, which
the `zenoh` driver republishes twice a second), as a payload controller switches it; a request unheard for
`REQUEST_TIMEOUT` s of wall time switches it off. Every sensor of the mission is built when the publisher starts
(as a vehicle powers its payload at boot), so a switch takes effect at the next step. The multibeam and the stereo
camera need MuJoCo (the `[sim]` extra); without it only the streams that can run are published, and
`unavailable` says which could not (a `stream_unavailable` event).
"""

from __future__ import annotations

import json
import threading
import time
from typing import Any

from mission.sensors import ros_msgs as ros
from mission.sensors.zenoh_keys import MBES_POINTS, SCANNER_POINTS, open_session
from mission.sim.vehicle import SimulatedVehicle

REQUEST_TIMEOUT = 3.0  # s of wall time
SENSORS = ("mbes", "stereo", "scanner")


class StreamPublisher:
    """Publishes a `SimulatedVehicle`'s payload frames under `prefix`; call `publish()` after each step."""

    def __init__(self, vehicle: SimulatedVehicle, listen: list[str], prefix: str = "auv/sim",
                 log: Any = None):
        self.vehicle = vehicle
        self.prefix = prefix.strip("/")
        self.log = log or (lambda event, **fields: None)
        self.published = dict.fromkeys(SENSORS, 0)
        self.unavailable: dict[str, str] = {}
        self._lock = threading.Lock()
        self._requests: dict[str, tuple[bool, float | None, float]] = {}  # sensor → (on, rate, wall time heard)
        self._applied: tuple[frozenset[str], float | None] = (frozenset(), None)
        self.session = open_session(listen=listen)
        self._pubs = {key: self.session.declare_publisher(f"{self.prefix}/{key}") for key in (
            MBES_POINTS, SCANNER_POINTS, "stereo/left/image_raw", "stereo/right/image_raw",
            "stereo/left/camera_info", "stereo/right/camera_info")}
        self._sub = self.session.declare_subscriber(f"{self.prefix}/*/request", self._on_request)
        self._power_up()

    def _power_up(self) -> None:
        """Build every sensor the mission has at start (a MuJoCo world, a camera), as a vehicle powers its payload
        at boot, so that switching one on later is immediate."""
        v = self.vehicle
        for sensor in SENSORS:
            if getattr(v.mission.sensors, sensor) is None:
                continue
            try:
                v.set_payload(frozenset({sensor}))
            except ImportError as exc:
                self.unavailable[sensor] = f"needs the [sim] extra ({exc.name or exc})"
                self.log("stream_unavailable", sensor=sensor, reason=self.unavailable[sensor])
        v.set_payload(frozenset())

    def _on_request(self, sample: Any) -> None:
        sensor = str(sample.key_expr).split("/")[-2]
        try:
            req = json.loads(sample.payload.to_bytes())
            rate = req.get("rate_hz")
            with self._lock:
                self._requests[sensor] = (bool(req.get("on")), float(rate) if rate is not None else None,
                                          time.monotonic())
        except (ValueError, TypeError, AttributeError):
            return

    def _apply_requests(self) -> None:
        now = time.monotonic()
        with self._lock:
            live = {s: r for s, r in self._requests.items() if now - r[2] <= REQUEST_TIMEOUT}
        wanted = frozenset(s for s, r in live.items() if r[0] and s in SENSORS and s not in self.unavailable)
        rate = live["stereo"][1] if "stereo" in live else None
        if (wanted, rate) == self._applied:
            return
        self._applied = (wanted, rate)
        v = self.vehicle
        if "mbes" in wanted and "mbes" not in v.payload:  # no burst of the pings "due" while it was off
            v.next_ping = max(v.next_ping, v.truth.time)
        v.set_payload(wanted)
        v.set_frame_rate(rate)
        self.log("payload_switched", sensors=sorted(wanted), frame_rate_hz=rate)

    def publish(self) -> None:
        """Switch the sensors as the drivers ask, then publish the frames the last step produced."""
        self._apply_requests()
        v = self.vehicle
        pings, v.pending_pings = v.pending_pings, []
        scans, v.pending_scans = v.pending_scans, []
        frames, v.pending_frames = v.pending_frames, []
        v.log.frames.clear()  # the truth of each frame's pose and scan: not kept by a server
        v.log.scans.clear()
        for p in pings:
            msg = ros.ray_cloud_msg(p.time, ros.mbes_directions(p.angles_deg), p.ranges, p.hit, "mbes")
            self._pubs[MBES_POINTS].put(ros.encode(msg))
        for s in scans:
            msg = ros.ray_cloud_msg(s.time, s.directions_body, s.ranges, s.hit, "base_link")
            self._pubs[SCANNER_POINTS].put(ros.encode(msg))
        for f in frames:
            h, w = f.left.shape[:2]
            for side, image in (("left", f.left), ("right", f.right)):
                info = ros.camera_info_msg(f.time, f.K, w, h, f.baseline, f"stereo_{side}", side == "right")
                self._pubs[f"stereo/{side}/camera_info"].put(ros.encode(info))
                self._pubs[f"stereo/{side}/image_raw"].put(ros.encode(ros.image_msg(f.time, image,
                                                                                    f"stereo_{side}")))
        self.published["mbes"] += len(pings)
        self.published["scanner"] += len(scans)
        self.published["stereo"] += len(frames)

    def close(self) -> None:
        try:
            self.session.close()
        except Exception:
            pass
