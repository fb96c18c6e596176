"""Payload streams attached to an onboard vehicle: `StreamedVehicle` adds the sensor products of the streams
(`mission.sensors.streams`) to the adapter's observations, and `SensorGuard` fails the element whose agent needs
a lost sensor (the executive then applies the element's `on_failure`).

The adapter keeps navigation and setpoints; a sensor with a stream is switched on and off through its driver
(never through the adapter, which is told only about the sensors without a stream). Every tick: the estimate
goes into the `NavTrack`, silent streams give `sensor_lost` (and `sensor_recovered`), and the frames whose stamps
the estimate has reached are handed to the agents, placed with the estimate at their stamps.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import Any

from mission.agents import Agent, AgentContext
from mission.sensors.navtrack import NavTrack
from mission.sensors.streams import SensorStream, split_frames
from mission.vehicle import Command, Observation
from mission.vehicles import OnboardVehicle


class StreamedVehicle:
    """An `OnboardVehicle` with payload streams (see the module docstring)."""

    def __init__(self, vehicle: OnboardVehicle, streams: Mapping[str, SensorStream], emit: Callable[..., None]):
        self.vehicle = vehicle
        self.streams = dict(streams)
        self.emit = emit
        self.control_period = vehicle.control_period
        self.track = NavTrack()
        self.payload: frozenset[str] = frozenset()
        self.rate_hz: float | None = None
        self._now = 0.0

    def lost(self) -> frozenset[str]:
        """The streamed sensors lost now."""
        return frozenset(name for name, s in self.streams.items() if s.lost)

    def observe(self) -> Observation:
        obs = self.vehicle.observe()
        nav = obs.nav
        self._now = nav.time
        self.track.add(nav)
        wall = time.monotonic()
        frames = []
        for name, stream in self.streams.items():
            change = stream.check(wall)
            if change == "lost":
                self.emit("sensor_lost", nav.time, sensor=name, driver=stream.uri, timeout_s=stream.timeout,
                          silent_s=round(wall - max(stream.last_arrival, stream.switched_on), 2))
            elif change == "recovered":
                self.emit("sensor_recovered", nav.time, sensor=name, driver=stream.uri)
            frames.extend(stream.collect(self.track, wall))
        sonar, stereo, scans = split_frames(frames)
        return replace(obs, sonar=obs.sonar + sonar, stereo=obs.stereo + stereo, scans=obs.scans + scans)

    def apply(self, command: Command) -> None:
        self.vehicle.apply(command)

    def set_aiding(self, usbl: bool) -> None:
        self.vehicle.set_aiding(usbl)

    def set_payload(self, sensors: frozenset[str]) -> None:
        self.payload = frozenset(sensors)
        for name, stream in self.streams.items():
            stream.switch(name in sensors, self.rate_hz if name == "stereo" else None)
        self.vehicle.set_payload(frozenset(s for s in sensors if s not in self.streams))

    def streams_off(self) -> None:
        """Switch every stream off (an element has ended; the executive switches the payload next)."""
        for stream in self.streams.values():
            stream.switch(False, None)

    def set_frame_rate(self, rate_hz: float | None) -> None:
        self.rate_hz = rate_hz
        stereo = self.streams.get("stereo")
        if stereo is not None:
            stereo.switch("stereo" in self.payload, rate_hz)
        else:
            self.vehicle.set_frame_rate(rate_hz)

    def advance(self) -> None:
        self.vehicle.advance()

    def close(self) -> None:
        try:
            for stream in self.streams.values():
                stream.close()
        finally:
            self.vehicle.close()

    def stream_metrics(self) -> dict[str, Any]:
        return {name: {"driver": s.uri, **s.stats.summary()} for name, s in self.streams.items()}


class SensorGuard(Agent):
    """Wraps an agent: when a sensor it has on is lost, the agent fails with `sensor lost: NAME`, and the vehicle
    is told to hold for that tick; when the element ends, `ended()` runs before the agent's own `stop` (the streams
    go off while a survey computes its products). Everything else is the wrapped agent's."""

    def __init__(self, inner: Agent, lost: Callable[[], frozenset[str]], ended: Callable[[], None] = lambda: None):
        super().__init__()
        self.inner = inner
        self.lost = lost
        self.ended = ended
        self.kind = inner.kind  # type: ignore[misc]
        self._sync()

    def _sync(self) -> None:
        i = self.inner
        self.status, self.reason, self.navigation = i.status, i.reason, i.navigation
        self.payload, self.frame_rate_hz, self.details = i.payload, i.frame_rate_hz, i.details

    def start(self, context: AgentContext) -> None:
        self.inner.start(context)
        self._sync()

    def step(self, observation: Observation) -> Command:
        gone = sorted(self.inner.payload & self.lost())
        if gone:
            self.inner.fail(f"sensor lost: {', '.join(gone)}")
            self._sync()
            return Command.hold(observation.nav)
        command = self.inner.step(observation)
        self._sync()
        return command

    def planned_path(self) -> list[tuple[float, float]]:
        return self.inner.planned_path()

    def stop(self) -> None:
        self.ended()  # the element is over: its streams stop before the agent works on its products
        self.inner.stop()
        self._sync()


def guarded_agents(factories: Mapping[str, Callable[[], Agent]], vehicle: StreamedVehicle
                   ) -> dict[str, Callable[[], Agent]]:
    """The agent factories, each agent wrapped in a `SensorGuard` of the vehicle's streams."""
    def guarded(factory: Callable[[], Agent]) -> Callable[[], Agent]:
        return lambda: SensorGuard(factory(), vehicle.lost, vehicle.streams_off)

    return {kind: guarded(factory) for kind, factory in factories.items()}
