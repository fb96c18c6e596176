"""The `zenoh` sensor driver: a mission sensor's stream from Zenoh key expressions (`mission.sensors.zenoh_keys`),
as a ROS 2 vehicle publishes them through `rmw_zenoh` or `auv sim serve --zenoh` does.

URI: `zenoh:PREFIX?connect=ENDPOINT` (e.g. `zenoh:auv/sim?connect=tcp/127.0.0.1:7447`), or `listen=ENDPOINT`
for the side that listens; both may repeat, comma-separated. Samples arrive on Zenoh's own threads, are decoded
there and handed to the sink; a stereo pair goes out when both images and both camera infos of one stamp have
come (pairs still incomplete when a newer stamp completes are dropped). The driver republishes its request
(on/off, frame rate) every `REQUEST_PERIOD` s so that a publisher that starts later still hears it.
"""

from __future__ import annotations

import json
import threading
from typing import Any

from mission.sensors import DriverContext, SensorError, split_query
from mission.sensors import ros_msgs as ros
from mission.sensors.zenoh_keys import STEREO_PARTS, open_session, request_key, sensor_keys

REQUEST_PERIOD = 0.5  # s of wall time
MAX_OPEN_PAIRS = 8  # stereo stamps waiting for their other parts


class StereoPairing:
    """Collects the four parts of each stereo stamp; returns the pair when one is complete."""

    def __init__(self) -> None:
        self.open: dict[int, dict[str, Any]] = {}

    def add(self, part: str, msg: Any) -> dict[str, Any] | None:
        stamp = int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec)
        parts = self.open.setdefault(stamp, {})
        parts[part] = msg
        if len(parts) < len(STEREO_PARTS):
            while len(self.open) > MAX_OPEN_PAIRS:
                del self.open[min(self.open)]
            return None
        for s in [s for s in self.open if s <= stamp]:
            del self.open[s]
        return parts


class ZenohDriver:
    """One sensor's subscription (see the module docstring)."""

    def __init__(self, address: str, context: DriverContext):
        prefix, query = split_query(address)
        if not prefix:
            raise SensorError(f"zenoh driver address '{address}' names no key prefix (e.g. auv/sim)")
        self.prefix = prefix.strip("/")
        self.context = context
        self.errors = 0
        self._pairing = StereoPairing()
        self._lock = threading.Lock()
        self._request: dict[str, Any] = {"on": False, "rate_hz": None}
        self._stop = threading.Event()

        def endpoints(name: str) -> list[str] | None:
            return [e for e in query[name].split(",") if e] if name in query else None

        self.session = open_session(listen=endpoints("listen"), connect=endpoints("connect"))
        self._subs = []
        try:
            for key in sensor_keys(self.prefix, context.sensor):
                part = key[len(self.prefix) + 1:].removeprefix("stereo/")
                self._subs.append(self.session.declare_subscriber(key, lambda s, p=part: self._on_sample(p, s)))
            self._pub = self.session.declare_publisher(request_key(self.prefix, context.sensor))
        except Exception:
            self.session.close()
            raise
        self._thread = threading.Thread(target=self._announce, name=f"zenoh-{context.sensor}-request", daemon=True)
        self._thread.start()

    def _on_sample(self, part: str, sample: Any) -> None:
        try:
            data = sample.payload.to_bytes()
            sensor = self.context.sensor
            if sensor == "mbes":
                self.context.sink(ros.sonar_from_msg(ros.decode(data, ros.CLOUD)))
            elif sensor == "scanner":
                max_range = float(getattr(self.context.settings, "max_range", 0.0))
                self.context.sink(ros.scan_from_msg(ros.decode(data, ros.CLOUD), max_range))
            else:
                msg = ros.decode(data, ros.IMAGE if part.endswith("image_raw") else ros.CAMERA_INFO)
                with self._lock:
                    parts = self._pairing.add(part, msg)
                if parts is not None:
                    self.context.sink(ros.stereo_from_msgs(parts["left/image_raw"], parts["right/image_raw"],
                                                           parts["left/camera_info"], parts["right/camera_info"]))
        except Exception:  # a malformed sample is counted, never the executive's crash
            self.errors += 1

    def _announce(self) -> None:
        while not self._stop.wait(REQUEST_PERIOD):
            self._put_request()

    def _put_request(self) -> None:
        with self._lock:
            payload = json.dumps(self._request)
        try:
            self._pub.put(payload.encode())
        except Exception:
            self.errors += 1

    def request(self, on: bool, rate_hz: float | None) -> None:
        with self._lock:
            changed = self._request != {"on": on, "rate_hz": rate_hz}
            self._request = {"on": on, "rate_hz": rate_hz}
        if changed:
            self._put_request()

    def close(self) -> None:
        self._stop.set()
        self._thread.join(2.0)
        try:
            self.session.close()
        except Exception:
            pass


def open_driver(address: str, context: DriverContext) -> ZenohDriver:
    """The `auv.sensors` factory for the scheme `zenoh`."""
    return ZenohDriver(address, context)
