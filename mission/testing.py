"""Test doubles that ship with the library: a stub vehicle, a scripted perception plug-in and a fake agent.

They let the executive, an agent or a plug-in host be tested alone, with no simulator, no MuJoCo and no sensors:

- `StubVehicle`: a kinematic point mass behind `VehicleInterface` (speed, yaw-rate and vertical-rate limits
  from the mission's vehicle, a flat seabed, no current). Its estimate is the truth. Faults are scripted
  (`StubFaults`): a lost link, a pilot takeover, an energy drain. It records what it was told.
- `ScriptedPlugin`: a `PerceptionPlugin` whose `process` returns scripted results in turn, raises a scripted
  exception, or sleeps first (to trip a host's time budget).
- `FakeAgent`: an agent that follows a script of `FakeStep`s (a command to send for so many ticks) and then
  succeeds, fails, or raises, at start or on a given tick.

>>> from mission.vehicle import Command
>>> v = StubVehicle(control_period=1.0, heading=90.0)    # facing east, at rest; 0.2 m/s² to 1 m/s takes 5 s
>>> v.apply(Command(heading=90.0, speed=1.0, depth=0.0))
>>> for _ in range(10):
...     v.advance()
>>> nav = v.observe().nav
>>> round(nav.time, 1), round(nav.north, 6), round(nav.east, 6)    # 0.2·(1+…+5) + 5·1 m
(10.0, 0.0, 8.0)
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from mission.agents.base import Agent, AgentContext
from mission.errors import LinkLostError
from mission.frames import wrap_deg
from mission.language.models import VehicleSettings
from mission.plugin_api import ReferencingResult, StereoImages
from mission.vehicle import HOVER_GAIN, STATION_KEEPING_SPEED_M_S, Command, NavState, Observation

YAW_GAIN = 1.0  # (deg/s) per deg of heading error, as the simulator's autopilot
DEPTH_GAIN = 0.4  # (m/s) per m of depth error


@dataclass(frozen=True)
class StubFaults:
    """Scripted vehicle faults, by (stub) time in seconds.

    `link_lost_at`: from then on `observe` and `advance` raise `LinkLostError`. `pilot_takeover`: (start, end)
    during which observations say `in_control=False` and commands are ignored. `energy_drain_wh_per_s`: extra
    energy drawn every second (an abnormal consumption for the energy monitor to catch).
    """

    link_lost_at: float | None = None
    pilot_takeover: tuple[float, float] | None = None
    energy_drain_wh_per_s: float = 0.0


@dataclass
class StubVehicle:
    """A kinematic point-mass vehicle with no sensors (see the module docstring); estimate = truth."""

    limits: VehicleSettings = field(default_factory=VehicleSettings)
    control_period: float = 0.2
    north: float = 0.0
    east: float = 0.0
    depth: float = 0.0
    heading: float = 0.0
    seabed_depth: float | None = 100.0  # a flat seabed (m); None: no bottom in range (altitude unknown)
    faults: StubFaults = field(default_factory=StubFaults)
    time: float = 0.0
    speed: float = 0.0
    energy_used_wh: float = 0.0
    command: Command | None = None
    commands: list[tuple[float, Command]] = field(default_factory=list)
    aiding: list[tuple[float, bool]] = field(default_factory=list)
    payloads: list[tuple[float, frozenset[str]]] = field(default_factory=list)
    frame_rates: list[tuple[float, float | None]] = field(default_factory=list)

    @classmethod
    def for_mission(cls, mission: Any, **options: Any) -> StubVehicle:
        """A stub at the mission's home, with its vehicle limits (`options` override any field)."""
        home = mission.home
        start = {"limits": mission.vehicle, "north": home.north, "east": home.east, "depth": home.depth,
                 "heading": home.heading}
        return cls(**{**start, **options})

    # --- VehicleInterface -------------------------------------------------------------------------------------
    def observe(self) -> Observation:
        self._check_link()
        altitude = self.seabed_depth - self.depth if self.seabed_depth is not None else None
        nav = NavState(time=self.time, north=self.north, east=self.east, depth=self.depth, heading=self.heading,
                       speed=self.speed, altitude=altitude, position_sigma=0.0,
                       energy_wh=self.limits.energy_wh - self.energy_used_wh)
        return Observation(nav, in_control=not self._taken_over())

    def apply(self, command: Command) -> None:
        self.commands.append((self.time, command))
        if not self._taken_over():
            self.command = command

    def set_aiding(self, usbl: bool) -> None:
        self.aiding.append((self.time, usbl))

    def set_payload(self, sensors: frozenset[str]) -> None:
        self.payloads.append((self.time, frozenset(sensors)))

    def set_frame_rate(self, rate_hz: float | None) -> None:
        self.frame_rates.append((self.time, rate_hz))

    def advance(self) -> None:
        self._check_link()
        dt, v = self.control_period, self.limits
        cmd = self.command or Command(heading=self.heading, speed=0.0)
        if cmd.altitude is not None and self.seabed_depth is not None:
            depth_cmd = self.seabed_depth - cmd.altitude
        else:
            depth_cmd = cmd.depth if cmd.depth is not None else self.depth
        if cmd.station is not None:
            en, ee = cmd.station[0] - self.north, cmd.station[1] - self.east
            gain = min(HOVER_GAIN, STATION_KEEPING_SPEED_M_S / max(math.hypot(en, ee), 1e-9))
            v_north, v_east = gain * en, gain * ee
            self.speed = math.hypot(v_north, v_east)
        else:
            target = min(max(cmd.speed, 0.0), v.max_speed)
            dv = v.max_acceleration * dt
            self.speed += min(max(target - self.speed, -dv), dv)
            rate = min(max(YAW_GAIN * wrap_deg(cmd.heading - self.heading), -v.max_yaw_rate), v.max_yaw_rate)
            self.heading = (self.heading + rate * dt) % 360.0
            h = math.radians(self.heading)
            v_north, v_east = self.speed * math.cos(h), self.speed * math.sin(h)
        w = min(max(DEPTH_GAIN * (depth_cmd - self.depth), -v.max_vertical_speed), v.max_vertical_speed)
        self.north += v_north * dt
        self.east += v_east * dt
        self.depth = max(self.depth + w * dt, 0.0)
        if self.seabed_depth is not None:
            self.depth = min(self.depth, self.seabed_depth)
        ratio = self.speed / v.cruise_speed
        power_w = v.hotel_power_w + v.propulsion_power_w * ratio**3
        self.energy_used_wh += power_w * dt / 3600.0 + self.faults.energy_drain_wh_per_s * dt
        self.time += dt

    # --- faults ----------------------------------------------------------------------------------------------
    def _check_link(self) -> None:
        lost = self.faults.link_lost_at
        if lost is not None and self.time >= lost:
            raise LinkLostError(f"stub vehicle: no heartbeat since t={lost:g} s")

    def _taken_over(self) -> bool:
        span = self.faults.pilot_takeover
        return span is not None and span[0] <= self.time < span[1]


class ScriptedPlugin:
    """A perception plug-in that returns `results` in turn (the last one repeats), after sleeping `sleep_s`.

    An item of `results` that is an exception instance is raised instead of returned. The plug-in records
    every call: `configured` (the settings), `frames` (the times of the frames processed), `requests`, and how
    often it was `reset` and `closed`.

    >>> p = ScriptedPlugin([ValueError("no features"), ReferencingResult(True, set_id="a")])
    >>> p.configure({})
    >>> frame = blank_frame(0.0)
    >>> try:
    ...     p.process(frame, None)
    ... except ValueError as e:
    ...     print(e)
    no features
    >>> p.process(frame, None).set_id, p.process(frame, None).set_id, len(p.frames)
    ('a', 'a', 3)
    """

    def __init__(self, results: Sequence[Any] = (), sleep_s: float = 0.0):
        self.results = list(results) or [ReferencingResult.not_recognised("scripted: nothing to return")]
        self.sleep_s = sleep_s
        self.configured: Mapping[str, Any] | None = None
        self.frames: list[float] = []
        self.requests: list[Any] = []
        self.resets = 0
        self.closed = 0

    def configure(self, settings: Mapping[str, Any]) -> None:
        self.configured = settings

    def process(self, frame: StereoImages, request: Any) -> Any:
        index = min(len(self.frames), len(self.results) - 1)
        self.frames.append(frame.time)
        self.requests.append(request)
        if self.sleep_s > 0:
            time.sleep(self.sleep_s)
        result = self.results[index]
        if isinstance(result, BaseException):
            raise result
        return result

    def reset(self) -> None:
        self.resets += 1

    def close(self) -> None:
        self.closed += 1


def blank_frame(t: float, width: int = 64, height: int = 48) -> StereoImages:
    """A black stereo pair at time `t` with a plausible camera (fx = width, baseline 0.2 m)."""
    import numpy as np

    K = np.array([[float(width), 0.0, width / 2], [0.0, float(width), height / 2], [0.0, 0.0, 1.0]])
    image = np.zeros((height, width), dtype=np.uint8)
    return StereoImages(t, image, image.copy(), K, 0.2)


@dataclass(frozen=True)
class FakeStep:
    """Send `command` for `ticks` control ticks; a None command holds the vehicle (`Command.hold`)."""

    ticks: int
    command: Command | None = None


class FakeAgent(Agent):
    """A scripted agent: it plays `script` and then ends as `outcome` says.

    `outcome` is "succeed", "fail" (with `reason`) or "run" (never ends: for timeouts and aborts). With
    `raise_on_start` the start raises it; with `raise_at_tick` (and `error`), that tick's step raises. It
    records what it saw: `context` (at start), `observations`, and whether `stopped`.
    """

    kind = "fake"

    def __init__(self, script: Iterable[FakeStep] = (), outcome: str = "succeed", reason: str = "scripted failure",
                 raise_on_start: BaseException | None = None, raise_at_tick: int | None = None,
                 error: BaseException | None = None, payload: Iterable[str] = (), navigation: str = "usbl",
                 path: Sequence[tuple[float, float]] = ()):
        super().__init__()
        if outcome not in ("succeed", "fail", "run"):
            raise ValueError(f"outcome must be succeed, fail or run, got {outcome!r}")
        self.script = [s for s in script for _ in range(s.ticks)]
        self.outcome, self.fail_reason = outcome, reason
        self.raise_on_start, self.raise_at_tick = raise_on_start, raise_at_tick
        self.error = error if error is not None else RuntimeError("scripted agent fault")
        self.payload = frozenset(payload)
        self.navigation = navigation
        self.path = [(float(n), float(e)) for n, e in path]
        self.context: AgentContext | None = None
        self.observations: list[Observation] = []
        self.stopped = False

    def start(self, context: AgentContext) -> None:
        self.context = context
        if self.raise_on_start is not None:
            raise self.raise_on_start

    def step(self, observation: Observation) -> Command:
        tick = len(self.observations)
        self.observations.append(observation)
        if self.raise_at_tick is not None and tick == self.raise_at_tick:
            raise self.error
        if tick < len(self.script):
            command = self.script[tick].command
            return command if command is not None else Command.hold(observation.nav)
        if self.outcome == "succeed":
            self.succeed()
        elif self.outcome == "fail":
            self.fail(self.fail_reason)
        return Command.hold(observation.nav)

    def planned_path(self) -> list[tuple[float, float]]:
        return list(self.path)

    def stop(self) -> None:
        self.stopped = True


def take_from(*agents: Agent) -> Callable[[], Agent]:
    """A factory that hands out the given agents in turn (one per route element of its kind)."""
    queue = list(agents)

    def factory() -> Agent:
        if not queue:
            raise RuntimeError("take_from: more elements than scripted agents")
        return queue.pop(0)

    return factory


__all__ = ["FakeAgent", "FakeStep", "ScriptedPlugin", "StubFaults", "StubVehicle", "blank_frame", "take_from"]
