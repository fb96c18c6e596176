"""A payload stream onboard: frames from a driver's own thread reach the agents placed at their stamps, a stream
that goes silent is lost within its sensor's timeout, and an agent that needs a lost sensor fails."""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable

import numpy as np
import pytest

from mission.agents import Agent, AgentContext
from mission.agents.base import Status
from mission.language.models import Mbes
from mission.onboard.streamed import SensorGuard
from mission.sensors import DriverContext, SensorFrame
from mission.sensors.navtrack import NavTrack
from mission.sensors.streams import SensorStream
from mission.vehicle import Command, NavState, Observation, SonarPing


def nav(t: float) -> NavState:
    """A vehicle heading east at 1 m/s: east = t."""
    return NavState(time=t, north=5.0, east=t, depth=20.0, heading=90.0, speed=1.0, altitude=10.0,
                    position_sigma=0.4, energy_wh=100.0)


def ping(t: float) -> SonarPing:
    n = 8
    nan = math.nan
    return SonarPing(t, np.full(n, 10.0), np.linspace(-60, 60, n), np.ones(n, bool), nan, nan, nan, nan, nan)


class ThreadDriver:
    """A driver that calls the sink from its own thread with the frames `make(i)` until it runs out or is closed;
    like a real sensor, it starts sending once it is asked to (so none come while the sensor is off)."""

    def __init__(self, context: DriverContext, make: Callable[[int], SensorFrame | None], period: float):
        self.context, self.make, self.period = context, make, period
        self.requests: list[tuple[bool, float | None]] = []
        self.stop = threading.Event()
        self.asked = threading.Event()
        self.thread = threading.Thread(target=self.run, daemon=True)
        self.thread.start()

    def run(self) -> None:
        i = 0
        if not self.asked.wait(5.0):
            return
        while not self.stop.wait(self.period):
            frame = self.make(i)
            if frame is None:
                return
            self.context.sink(frame)
            i += 1

    def request(self, on: bool, rate_hz: float | None) -> None:
        self.requests.append((on, rate_hz))
        if on:
            self.asked.set()

    def close(self) -> None:
        self.stop.set()
        self.asked.set()
        self.thread.join(1.0)


def stream_of(make: Callable[[int], SensorFrame | None], period: float = 0.005, timeout: float = 0.3
              ) -> tuple[SensorStream, list[ThreadDriver]]:
    drivers: list[ThreadDriver] = []

    def opener(uri: str, context: DriverContext) -> ThreadDriver:
        drivers.append(ThreadDriver(context, make, period))
        return drivers[-1]

    return SensorStream("mbes", "test:thread", Mbes(), timeout, opener), drivers


def test_pings_are_placed_with_the_estimate_at_their_own_stamps() -> None:
    stream, drivers = stream_of(lambda i: ping(0.05 + 0.1 * i) if i < 10 else None)
    stream.switch(True, None)
    track = NavTrack()
    for k in range(6):
        track.add(nav(0.2 * k))
    time.sleep(0.3)
    frames = stream.collect(track, time.monotonic())
    stream.close()
    stamps = [f.time for f in frames]
    assert stamps == pytest.approx([0.05 + 0.1 * i for i in range(10)])  # up to t = 0.95 ≤ the estimate's 1.0
    for f in frames:
        assert isinstance(f, SonarPing)
        assert (f.north, f.east, f.depth, f.heading) == pytest.approx((5.0, f.time, 20.0, 90.0))
    assert drivers[0].requests == [(True, None)]


def test_a_frame_ahead_of_the_estimate_is_delivered_on_a_later_tick() -> None:
    stream, _ = stream_of(lambda i: ping(1.1) if i == 0 else None)
    stream.switch(True, None)
    track = NavTrack()
    track.add(nav(1.0))
    time.sleep(0.1)
    assert stream.collect(track, time.monotonic()) == []
    track.add(nav(1.2))
    later = stream.collect(track, time.monotonic())
    stream.close()
    assert [f.time for f in later] == [1.1]
    assert later[0].east == pytest.approx(1.1)  # type: ignore[union-attr]


def test_a_stream_faster_than_its_consumer_drops_the_oldest_and_counts_them() -> None:
    stream, _ = stream_of(lambda i: ping(0.001 * i) if i < 400 else None, period=0.0005)
    stream.switch(True, None)
    track = NavTrack()
    track.add(nav(0.0))
    track.add(nav(1.0))
    time.sleep(1.0)
    frames = stream.collect(track, time.monotonic())
    stream.close()
    assert len(frames) == stream.queue.capacity
    assert frames[-1].time == pytest.approx(0.399)  # the newest survive
    assert stream.stats.dropped == 400 - stream.queue.capacity
    assert stream.stats.received == 400


def test_a_silent_stream_is_lost_within_its_timeout_and_recovers_when_it_speaks_again() -> None:
    resume = threading.Event()

    def make(i: int) -> SonarPing | None:
        if i >= 5 and not resume.wait(5.0):  # the source stops after five pings until resumed
            return None
        return ping(0.01 * i)

    stream, _ = stream_of(make, period=0.01, timeout=0.3)
    stream.switch(True, None)
    start = time.monotonic()
    time.sleep(0.1)
    assert stream.check(time.monotonic()) == ""
    lost_at = None
    while time.monotonic() - start < 2.0:
        if stream.check(time.monotonic()) == "lost":
            lost_at = time.monotonic()
            break
        time.sleep(0.01)
    assert lost_at is not None
    assert lost_at - stream.last_arrival == pytest.approx(0.3, abs=0.1)  # silent for its timeout, not longer
    resume.set()
    time.sleep(0.1)
    assert stream.check(time.monotonic()) == "recovered"
    stream.close()
    assert stream.stats.lost_events == 1


def test_a_sensor_switched_on_that_never_speaks_is_lost_after_its_timeout_and_the_start_up_grace(
        monkeypatch: pytest.MonkeyPatch) -> None:
    from mission.sensors import streams

    monkeypatch.setattr(streams, "STARTUP_GRACE_S", 0.2)
    stream, _ = stream_of(lambda i: None, timeout=0.3)
    stream.switch(True, None)
    assert stream.check(stream.switched_on + 0.45) == ""
    assert stream.check(stream.switched_on + 0.55) == "lost"
    stream.close()


def test_a_stream_that_is_off_is_never_lost() -> None:
    stream, _ = stream_of(lambda i: None)
    time.sleep(0.4)
    assert stream.check(time.monotonic()) == ""
    stream.close()


class SonarAgent(Agent):
    kind = "survey"

    def start(self, context: AgentContext) -> None:
        self.payload = frozenset({"mbes"})

    def step(self, observation: Observation) -> Command:
        return Command(heading=90.0, speed=1.5, depth=20.0)


def test_an_agent_whose_sensor_is_lost_fails_and_the_vehicle_holds() -> None:
    lost: frozenset[str] = frozenset()
    agent = SensorGuard(SonarAgent(), lambda: lost)
    agent.start(None)  # type: ignore[arg-type]
    assert agent.payload == frozenset({"mbes"})
    assert agent.step(Observation(nav(1.0))).speed == 1.5
    lost = frozenset({"mbes", "stereo"})
    command = agent.step(Observation(nav(1.2)))
    assert (agent.status, agent.reason) == (Status.FAILED, "sensor lost: mbes")
    assert command.speed == 0.0
