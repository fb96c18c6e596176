"""The payload streams of an onboard run: one driver per mission sensor that names a `driver:`, each feeding a
bounded queue (`DropOldestQueue`) from its own thread, watched for silence, and drained by the control loop.

`collect(track)` hands out the frames whose stamps the navigation estimate has reached, pings and scans placed
with the estimate interpolated to their stamp (`NavTrack.at`); a frame ahead of the estimate waits for the next
tick. A stream that is on and has delivered nothing for its sensor's `timeout` (wall seconds: a stream's silence
is the host's to see) is lost: `check` reports it once; a frame arriving later recovers it. A sensor just switched
on has `STARTUP_GRACE_S` more for its first frame (the request has to reach it, and it has to start). Nothing
here blocks.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

from mission.language.models import Mission
from mission.plugin_api import StereoImages
from mission.sensors import SENSOR_NAMES, DriverContext, SensorDriver, SensorFrame, open_driver
from mission.sensors.navtrack import NavTrack
from mission.sensors.queue import DropOldestQueue
from mission.vehicle import ScanFrame, SonarPing

QUEUE_FRAMES = {"mbes": 256, "scanner": 32, "stereo": 4}  # ~1 MB, ~2 MB, ~9 MB at the reference sizes
MAX_WAIT_S = 2.0  # s of vehicle time a frame may wait for the estimate to reach its stamp
STARTUP_GRACE_S = 3.0  # s of wall time a sensor just switched on has, beyond its timeout, for its first frame


@dataclass
class StreamStats:
    """What one stream did over a run (for metrics.json)."""

    received: int = 0
    delivered: int = 0
    dropped: int = 0  # oldest frames dropped by a full queue or a consumer that fell behind
    stale: int = 0  # frames far ahead of the navigation estimate's clock
    ignored: int = 0  # frames that came while the sensor was off
    lost_events: int = 0
    latency_s: list[float] = field(default_factory=list)  # wall arrival → delivery to the agents

    def summary(self) -> dict[str, Any]:
        lat = sorted(self.latency_s)
        return {"received": self.received, "delivered": self.delivered, "dropped": self.dropped,
                "stale": self.stale, "ignored_while_off": self.ignored, "lost_events": self.lost_events,
                "queue_latency_median_s": round(lat[len(lat) // 2], 4) if lat else None}


class SensorStream:
    """One sensor's driver, queue and silence watch."""

    def __init__(self, sensor: str, uri: str, settings: Any, timeout: float,
                 opener: Callable[[str, DriverContext], SensorDriver] = open_driver):
        self.sensor = sensor
        self.uri = uri
        self.timeout = timeout
        self.queue: DropOldestQueue[tuple[float, SensorFrame]] = DropOldestQueue(QUEUE_FRAMES.get(sensor, 16))
        self.waiting: list[tuple[float, SensorFrame]] = []
        self.stats = StreamStats()
        self.on = False
        self.lost = False
        self.switched_on = time.monotonic()
        self.last_arrival = -math.inf
        self.driver = opener(uri, DriverContext(sensor, settings, self._take))

    def _take(self, frame: SensorFrame) -> None:
        """The driver's thread: queue the frame (the oldest goes when full) and note when it came; a frame that
        comes while the sensor is off is ignored (counted)."""
        now = time.monotonic()
        self.last_arrival = now
        self.stats.received += 1
        if not self.on:
            self.stats.ignored += 1
            return
        self.queue.put((now, frame))

    def switch(self, on: bool, rate_hz: float | None) -> None:
        if on and not self.on:
            self.switched_on = time.monotonic()
            self.queue.drain()  # frames from while it was off are not wanted
        self.on = on
        self.driver.request(on, rate_hz)

    def silent_for(self, now: float) -> float:
        """Seconds without a frame; since the switch-on, less the start-up grace, while none has come since."""
        if self.last_arrival >= self.switched_on:
            return now - self.last_arrival
        return now - self.switched_on - STARTUP_GRACE_S

    def check(self, now: float) -> str:
        """`lost` when the stream has just gone silent for its timeout, `recovered` when it speaks again."""
        if not self.on:
            return ""
        if not self.lost and self.silent_for(now) > self.timeout:
            self.lost = True
            self.stats.lost_events += 1
            return "lost"
        if self.lost and self.silent_for(now) <= self.timeout:
            self.lost = False
            return "recovered"
        return ""

    def collect(self, track: NavTrack, now: float) -> list[SensorFrame]:
        """Frames the estimate has reached, placed at their stamps (oldest first)."""
        self.waiting.extend(self.queue.drain())
        cap = self.queue.capacity
        if len(self.waiting) > cap:  # the consumer fell behind: the oldest go
            self.stats.dropped += len(self.waiting) - cap
            self.waiting = self.waiting[-cap:]
        out: list[SensorFrame] = []
        keep: list[tuple[float, SensorFrame]] = []
        latest = track.latest_time
        for arrived, frame in self.waiting:
            if not self.on:
                self.stats.ignored += 1
                continue
            if isinstance(frame, StereoImages):
                out.append(frame)
                self.stats.latency_s.append(now - arrived)
                continue
            nav = track.at(frame.time)
            if nav is None:
                if latest is not None and frame.time - latest > MAX_WAIT_S:
                    self.stats.stale += 1  # a clock far ahead of the estimate's: not this vehicle's
                else:
                    keep.append((arrived, frame))
                continue
            out.append(replace(frame, north=nav.north, east=nav.east, depth=nav.depth, heading=nav.heading,
                               position_sigma=nav.position_sigma))
            self.stats.latency_s.append(now - arrived)
        self.waiting = keep
        if len(self.stats.latency_s) > 10_000:
            self.stats.latency_s = self.stats.latency_s[-5_000:]
        self.stats.delivered += len(out)
        return out

    def close(self) -> None:
        self.stats.dropped += self.queue.dropped
        self.driver.close()


def open_streams(mission: Mission, overrides: dict[str, str] | None = None,
                 opener: Callable[[str, DriverContext], SensorDriver] = open_driver) -> dict[str, SensorStream]:
    """A stream for every mission sensor with a driver (the mission's `driver:`, or `overrides[sensor]`)."""
    streams: dict[str, SensorStream] = {}
    try:
        for name in SENSOR_NAMES:
            settings = getattr(mission.sensors, name)
            if settings is None:
                continue
            uri = (overrides or {}).get(name) or settings.driver
            if uri:
                streams[name] = SensorStream(name, uri, settings, settings.timeout, opener)
    except BaseException:
        for s in streams.values():
            s.close()
        raise
    return streams


def split_frames(frames: list[SensorFrame]) -> tuple[tuple[SonarPing, ...], tuple[StereoImages, ...],
                                                     tuple[ScanFrame, ...]]:
    return (tuple(f for f in frames if isinstance(f, SonarPing)),
            tuple(f for f in frames if isinstance(f, StereoImages)),
            tuple(f for f in frames if isinstance(f, ScanFrame)))
