"""The tactical-agent contract (seed 002 §1: the tactical level runs one agent per route element).

The executive owns the loop. An agent implements five calls:

- `start(context)`: once, when its element begins; plan here from the estimated state in `context`.
- `step(observation) -> Command`: every control tick; decide the autopilot setpoints.
- `status`: RUNNING until the agent has SUCCEEDED or FAILED (with `reason`).
- `planned_path()`: the (north, east) polyline it intends to follow, for logs and plots.
- `stop()`: when the element ends for any reason (done, timeout, abort); release what it holds.
"""

from __future__ import annotations

import abc
import enum
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import ClassVar

from mission.agents.report import AgentReport
from mission.artifacts import Artifacts
from mission.knowledge import Knowledge
from mission.language.models import Mission, RouteElement
from mission.plugin_host import PluginHost
from mission.vehicle import Command, NavState, Observation


class Status(enum.Enum):
    RUNNING = "running"
    SUCCEEDED = "succeeded"
    FAILED = "failed"


@dataclass(frozen=True)
class AgentContext:
    """What an agent may know when it starts: the mission, its element, the estimate, and an event emitter."""

    mission: Mission
    element: RouteElement
    nav: NavState
    emit: Callable[..., None] = field(default=lambda *a, **k: None)
    knowledge: Knowledge = field(default_factory=Knowledge)
    plugins: PluginHost | None = None
    artifacts: Artifacts = field(default_factory=Artifacts)


class Agent(abc.ABC):
    """Base class with no-op defaults for `planned_path` and `stop`; subclasses set `kind` and implement the
    two abstract calls, `start` and `step`."""

    kind: ClassVar[str] = ""

    def __init__(self) -> None:
        self.status: Status = Status.RUNNING
        self.reason: str = ""
        self.navigation: str = "usbl"  # "usbl" or "dead-reckoning": which aiding the agent asks for
        self.payload: frozenset[str] = frozenset()  # payload sensors the agent needs on now ("mbes", "stereo")
        self.frame_rate_hz: float | None = None  # stereo frames per second wanted (None: the camera's own rate)
        self.details: AgentReport = AgentReport()  # element results for metrics (a dataclass per agent kind)

    @abc.abstractmethod
    def start(self, context: AgentContext) -> None:
        """Plan from the estimated state in `context`; called once when the element begins."""

    @abc.abstractmethod
    def step(self, observation: Observation) -> Command:
        """The autopilot setpoints for this tick."""

    def planned_path(self) -> list[tuple[float, float]]:
        return []

    def stop(self) -> None:
        return None

    def succeed(self) -> None:
        self.status = Status.SUCCEEDED

    def fail(self, reason: str) -> None:
        self.status, self.reason = Status.FAILED, reason
