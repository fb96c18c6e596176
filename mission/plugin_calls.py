"""The calls of one plug-in role, in order, on its worker process: when each is ready, and what a fault does.

A role's calls go to its worker in submission order and are answered in that order. The item at the head of
the queue is the one the worker is running; it started when the worker became ready or answered the item before
it (as seen by the host, which reads answers at every host call: a late read only makes the deadline later).

Faults, each a `plugin_fault` event and the role's "no answer" result for the call:
- the plug-in raised (the worker lives on);
- the call was over its budget (`Timing.budget_s`: wall time onboard, the worker's CPU time in simulation);
  its result is dropped and the worker lives on, its state advanced by the call;
- the worker crashed (segfault, `os._exit`), or did not answer within the hard timeout (wall time): the worker
  is killed and a fresh one is started and configured; the calls queued behind are re-sent to it, so the
  restarted plug-in starts from `configure` (a VO chain restarts at the next frame). The fault's result says
  so (`details["worker_restarted"]`).
A replacement worker that cannot start (`configure` raises or times out) breaks the role: one fault, and from
then on every call is answered "no answer" at once, without more events.

Two clocks (`Timing.simulated`). Onboard, a result is ready when its answer has arrived. In simulation the
simulator is paused while code thinks, so the call's cost is charged to the simulated clock: ready at
`max(submitted, worker free) + latency`. With a modelled latency (`Timing.latency_s`, the simulator's default)
every call is charged that latency, and a worker's restart `RESTART_CHARGE_S`, so that a run repeats exactly for
its seed on any machine under any load. With `latency_s` None the latency is the worker's CPU time for the call
rounded up to `quantum_s`, and a restart its start-up CPU time rounded up to 0.1 s: closer to what this plug-in
costs, but a run then depends on the machine. Either way a crash is charged one quantum and a hang the budget, and
the measured CPU times are kept (`RoleWorker.cpu_s`) for the run's metrics.
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

from mission.errors import PluginError
from mission.plugin_api import OdometryResult, ReferencingResult
from mission.plugin_worker import Message, WorkerProcess

RESTART_QUANTUM_S = 0.1
SIMULATED_LATENCY_S = 0.1  # the simulator's modelled latency of a call: ready at the next 0.2 s control tick
RESTART_CHARGE_S = 1.0  # a modelled restart: start a process, import and configure the plug-in


@dataclass(frozen=True)
class Timing:
    """How a host times its calls (see the module docstring)."""

    simulated: bool = False
    budget_s: float = 5.0
    hard_timeout_s: float = 5.0  # after this a running call is abandoned and its worker killed: wall time onboard,
    # the worker's CPU time in simulation (so that a loaded machine never changes a run)
    wall_limit_s: float = 600.0  # simulation: a call that neither answers nor burns CPU (a deadlock) for this long
    quantum_s: float = 0.01  # simulation: charged latencies are rounded up to a multiple of this
    start_timeout_s: float = 60.0  # wall time a worker may take to import and configure its plug-in
    latency_s: float | None = None  # simulation: every call's modelled latency (None: its CPU time)

    def charge(self, cpu_s: float, quantum_s: float | None = None) -> float:
        """Simulation: the latency charged for a call that took `cpu_s` of CPU."""
        if self.latency_s is not None:
            return self.latency_s
        q = self.quantum_s if quantum_s is None else quantum_s
        return max(1, math.ceil(cpu_s / q - 1e-9)) * q

    def charge_restart(self, cpu_s: float) -> float:
        """Simulation: the time charged for restarting a worker whose start-up took `cpu_s` of CPU."""
        return RESTART_CHARGE_S if self.latency_s is not None else self.charge(cpu_s, RESTART_QUANTUM_S)


class PluginCall:
    """A plug-in call under way. `poll(now)` is None until the result is ready at the vehicle's time `now`."""

    def __init__(self, role: str, frame_time: float, result: Any = None, ready_at: float = float("inf")):
        self.role = role
        self.frame_time = frame_time
        self._result = result
        self._ready_at = ready_at
        self._answered = result is not None
        self._waiter: Callable[[PluginCall, float], Any] | None = None
        self.submitted_at = frame_time  # the vehicle's time at submission (set by the host)

    @property
    def answered(self) -> bool:
        """The worker has answered (or the call has failed); in simulation it may still not be ready."""
        return self._answered

    @property
    def ready_at(self) -> float:
        return self._ready_at

    def resolve(self, result: Any, ready_at: float) -> None:
        self._result, self._ready_at, self._answered = result, ready_at, True

    def poll(self, now: float) -> Any | None:
        if self._waiter is not None:
            return self._waiter(self, now)
        return self._result if now >= self._ready_at else None


@dataclass
class _Item:
    """A message for the worker that waits for its answer: a call, or a reset (`call` None)."""

    message: Message
    call: PluginCall | None = None


@dataclass
class Fault:
    """A `plugin_fault` to emit: at `due` (simulated time) or, onboard (`due` None), when the host notices."""

    due: float | None
    fields: dict[str, Any] = field(default_factory=dict)


class RoleWorker:
    """One role's worker process and its queue of calls."""

    def __init__(self, role: str, spec: str, settings: Mapping[str, Any], timing: Timing):
        self.role, self.spec, self.settings, self.timing = role, spec, settings, timing
        self.pending: deque[_Item] = deque()
        self.faults: list[Fault] = []
        self.broken: str | None = None
        self.free_at = -math.inf  # simulation: when the worker is done with what it has been given
        self.cpu_s: list[float] = []  # the CPU time of each answered call, as measured in the worker
        self.fault_count = 0
        self._seq = 0
        self._dying: list[WorkerProcess] = []
        self._charge_start = False
        self._start()

    # -- lifecycle ---------------------------------------------------------------------------------------------
    def _start(self) -> None:
        self.worker = WorkerProcess(self.spec, dict(self.settings))
        self.ready = False
        self.head_since = math.inf
        self.head_cpu: float | None = None

    def wait_ready(self, deadline: float) -> None:
        """Block until the first worker has configured its plug-in (raises PluginError if it cannot)."""
        while not self.ready:
            remaining = deadline - time.monotonic()
            messages = self.worker.receive(max(0.0, min(remaining, 0.5)))
            for message in messages:
                if message[0] == "start_failed":
                    raise PluginError(str(message[1]))
                self._handle(message)
            if self.ready:
                return
            if self.worker.ended or not self.worker.process.is_alive():
                self.worker.process.join(1.0)
                raise PluginError(f"perception plug-in '{self.spec}' ({self.role}) failed to start: its worker "
                                  f"{self.worker.exit_description()}")
            if remaining <= 0:
                raise PluginError(f"perception plug-in '{self.spec}' ({self.role}) did not start within "
                                  f"{self.timing.start_timeout_s:g} s")

    def _restart(self) -> None:
        self.worker.kill()
        self._dying.append(self.worker)
        self._start()
        self._charge_start = True
        for item in self.pending:
            self.worker.send(item.message)

    def close(self, deadline: float) -> None:
        """Ask the worker to close its plug-in and exit; kill it at `deadline` (monotonic); reap every worker.
        The role is then out of service: nothing restarts it."""
        self.broken = "the plug-in host was closed"
        if not self.worker.ended:
            self.worker.send(("close",))
            while not self.worker.ended and time.monotonic() < deadline:
                for message in self.worker.receive(min(0.2, max(0.0, deadline - time.monotonic()))):
                    if message[0] == "closed" and message[1] is not None:
                        self._fault(None, f"close raised {message[1]}", 0.0, None)
                    if message[0] == "closed":
                        self.worker.ended = True
        self.worker.stop(deadline)
        for old in self._dying:
            old.stop(time.monotonic() + 5.0)
        self._dying.clear()
        for item in self.pending:
            if item.call is not None:
                item.call.resolve(no_answer(self.role, "the plug-in host was closed"), item.call.submitted_at)
        self.pending.clear()

    # -- calls -------------------------------------------------------------------------------------------------
    def submit(self, call: PluginCall, frame: Any, request: Any) -> None:
        self.pump()  # a worker that died while idle is replaced before it is given the call
        if self.broken is not None:
            call.resolve(no_answer(self.role, f"plug-in unavailable: {self.broken}"), call.submitted_at)
            return
        self._seq += 1
        self._queue(_Item(("process", self._seq, frame, request), call))

    def reset(self) -> None:
        if self.broken is None:
            self._queue(_Item(("reset",)))

    def _queue(self, item: _Item) -> None:
        if not self.pending and self.ready:
            self._head_started()
        self.pending.append(item)
        self.worker.send(item.message)

    def lower_bound(self, call: PluginCall) -> float:
        """Simulation: the earliest time `call` can be ready, known without waiting for the worker."""
        return max(call.submitted_at, self.free_at) + min(self.timing.quantum_s, self.timing.charge(0.0))

    def pump(self, timeout: float = 0.0) -> None:
        """Read what the worker has sent (waiting up to `timeout` s for it), then act on a crash or a hang."""
        self._dying = [w for w in self._dying if not w.reap()]
        if self.broken is not None:
            return
        for message in self.worker.receive(timeout):
            self._handle(message)
        if self.broken is not None:
            return
        if self.worker.ended or not self.worker.process.is_alive():
            for message in self.worker.receive(0.0):  # what it sent before it died
                self._handle(message)
            self._lost(f"its worker {self.worker.exit_description()}", crashed=True)
        elif not self.ready and time.monotonic() - self.worker.started_wall > self.timing.start_timeout_s:
            self._lost(f"its worker did not start within {self.timing.start_timeout_s:g} s", crashed=True)
        elif self.pending and (why := self._hung()):
            self._lost(why, crashed=False)

    def _head_started(self) -> None:
        """The item at the head of the queue starts now (as far as the host can tell)."""
        self.head_since = time.monotonic()
        self.head_cpu = self.worker.cpu_s() if self.timing.simulated else None

    def _hung(self) -> str:
        """Why the call at the head counts as hung ("" while it does not): onboard, no answer within the hard
        timeout of wall time; in simulation, the hard timeout of the worker's CPU time spent on it, or the wall
        limit (a call that burns no CPU and never answers)."""
        t = self.timing
        waited = time.monotonic() - self.head_since
        if not t.simulated:
            return f"no answer within {t.hard_timeout_s:g} s (wall clock)" if waited > t.hard_timeout_s else ""
        cpu = self.worker.cpu_s()
        if cpu is not None and self.head_cpu is not None and cpu - self.head_cpu > t.hard_timeout_s:
            return f"no answer within {t.hard_timeout_s:g} s of CPU time"
        return f"no answer within {t.wall_limit_s:g} s (wall clock)" if waited > t.wall_limit_s else ""

    def next_deadline(self) -> float:
        """The wall time (monotonic) at which `pump` will act on a hang if no answer comes."""
        if not self.ready:
            return self.worker.started_wall + self.timing.start_timeout_s
        if not self.pending:
            return math.inf
        if self.timing.simulated:  # CPU time is checked at each wake-up: wake at least every second
            return min(time.monotonic() + 1.0, self.head_since + self.timing.wall_limit_s)
        return self.head_since + self.timing.hard_timeout_s

    def _handle(self, message: Message) -> None:
        kind = message[0]
        if kind == "ready":
            self.ready = True
            self._head_started()
            if self._charge_start and self.timing.simulated:
                self.free_at += self.timing.charge_restart(float(message[1]))
            self._charge_start = False
        elif kind == "start_failed":
            self._break(f"restart failed: {message[1]}")
        elif kind in ("answer", "raised"):
            item = self.pending.popleft()
            assert item.call is not None and item.message[1] == message[1], (item.message, message[:2])
            self._head_started()
            self._answered(item.call, kind == "answer", message[2], float(message[3]), float(message[4]))
        elif kind == "reset":
            self.pending.popleft()
            self._head_started()
            if message[1] is not None:
                self._fault(None, f"reset raised {message[1]}", 0.0, None)

    def _answered(self, call: PluginCall, ok: bool, payload: Any, cpu_s: float, wall_s: float) -> None:
        t = self.timing
        self.cpu_s.append(cpu_s)
        spent = cpu_s if t.simulated else wall_s
        start = max(call.submitted_at, self.free_at)
        ready = start + (t.charge(cpu_s) if spent <= t.budget_s else t.budget_s)
        if t.simulated:
            self.free_at = ready
        else:
            ready = -math.inf
        if not ok:
            self._fail(call, f"plug-in fault: {payload}", 1e3 * spent, ready)
        elif spent > t.budget_s:
            self._fail(call, f"over its time budget ({1e3 * spent:.0f} ms > {1e3 * t.budget_s:.0f} ms)",
                       1e3 * spent, ready)
        else:
            call.resolve(payload, ready)

    def _lost(self, why: str, crashed: bool) -> None:
        """The worker crashed or hung: fail the call it was running, restart it, re-send the rest."""
        if not self.ready and self._charge_start:  # a replacement that cannot start: give up on this role
            self.worker.kill()
            self._dying.append(self.worker)
            self._break(f"restart failed: {why}")
            return
        t = self.timing
        item = self.pending.popleft() if self.pending and self.ready else None
        elapsed_ms = 1e3 * max(0.0, time.monotonic() - self.head_since) if item is not None else 0.0
        self._restart()
        if item is None:
            self._fault(None, f"worker lost while idle: {why}", 0.0, None, worker_restarted=True)
            return
        ready = max(item.call.submitted_at if item.call else -math.inf, self.free_at) + (
            t.quantum_s if crashed else t.budget_s)
        if t.simulated:
            self.free_at = ready
            elapsed_ms = 1e3 * (t.quantum_s if crashed else t.budget_s)
        if item.call is not None:
            self._fail(item.call, why, elapsed_ms, ready if t.simulated else -math.inf, worker_restarted=True)
        else:
            due = ready if t.simulated and math.isfinite(ready) else None
            self._fault(None, f"reset: {why}", elapsed_ms, due, worker_restarted=True)

    def _break(self, why: str) -> None:
        self.broken = why
        self._fault(None, why, 0.0, self.free_at if self.timing.simulated and self.free_at > -math.inf else None)
        for item in self.pending:
            if item.call is not None:
                item.call.resolve(no_answer(self.role, f"plug-in unavailable: {why}"),
                                  max(item.call.submitted_at, self.free_at))
        self.pending.clear()

    def _fail(self, call: PluginCall, why: str, elapsed_ms: float, ready: float, **details: Any) -> None:
        call.resolve(no_answer(self.role, why, elapsed_ms=elapsed_ms, **details), ready)
        self._fault(call, why, elapsed_ms, ready if self.timing.simulated else None, **details)

    def _fault(self, call: PluginCall | None, why: str, elapsed_ms: float, due: float | None,
               **details: Any) -> None:
        self.fault_count += 1
        fields: dict[str, Any] = {"plugin": self.spec, "role": self.role, "error": why,
                                  "elapsed_ms": round(elapsed_ms, 1), **details}
        if call is not None:
            fields["frame_time"] = call.frame_time
        self.faults.append(Fault(due, fields))


def no_answer(role: str, reason: str, **details: Any) -> ReferencingResult | OdometryResult:
    """The "no answer" result of a role: lost tracking for odometry, "not recognised" otherwise."""
    if role == "odometry":
        return OdometryResult.lost(reason, **details)
    return ReferencingResult.not_recognised(reason, **details)
