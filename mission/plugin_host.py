"""The executive's side of perception plug-ins: each configured plug-in runs in its own worker process, out of
the control loop, and its faults are contained (issue 19, item 4).

Agents hand frames over with `submit(role, frame, request, now)` and read the result with `PluginCall.poll(now)`;
nothing the plug-in does (think for long, hang, raise, segfault) stalls the caller. Calls of one role are
answered in submission order, each result tagged with its frame's time (`call.frame_time`). A fault (see
`mission.plugin_calls`) gives the role's "no answer" result (`ReferencingResult.not_recognised`,
`OdometryResult.lost`) and a `plugin_fault` event: `emit("plugin_fault", time, plugin=…, role=…, error=…,
elapsed_ms=…, frame_time=…)`.

Two clocks (`simulated_clock`):
- onboard (`auv run`, the default): `now` is the vehicle's time; a result is ready as soon as it has arrived, and
  `poll` never blocks. The budget is wall time, and a call still running at `budget_s` is abandoned and its
  worker restarted (the hard timeout is the budget).
- simulation (`auv simulate`): the simulator is paused while code thinks, so a call's latency is charged to the
  simulated clock: `latency_s` (a modelled latency, so that a run repeats exactly for its seed) or, with
  `latency_s` None, the worker's CPU time rounded up to `quantum_s` (default 10 ms). `poll(now)` is None before
  the call can be ready, and when `now` may have reached its ready time it blocks until the worker has answered
  (at most the hard timeout). The budget is the worker's CPU time, and so is the hard timeout,
  `max(3 × budget_s, 30 s)`: a loaded machine stretches a call's wall time, never its CPU time, so it never kills a
  healthy call and a run repeats; a call that burns no CPU and never answers (a deadlock) is abandoned after
  `Timing.wall_limit_s` (600 s) of wall time.

`process` (synchronous: submit and wait for the answer) serves tools and benches. `reset()` is queued behind the
calls already submitted; `close()` asks each worker to close its plug-in and exit, and kills it after
`close_timeout_s`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping
from typing import Any

from mission.plugin_api import StereoImages
from mission.plugin_calls import PluginCall, RoleWorker, Timing, no_answer

DEFAULT_BUDGET_S = 5.0  # per call; generous for a software renderer's machine, tight enough to catch a hang
SIMULATED_HARD_TIMEOUT_S = 30.0  # simulation's hard timeout (CPU time) is at least this, and 3 × the budget


class PluginHost:
    """Plug-in workers by role (`referencing`, `odometry`), each call timed and guarded."""

    def __init__(self, roles: Mapping[str, str | None], settings: Mapping[str, Any], emit: Callable[..., None],
                 budget_s: float = DEFAULT_BUDGET_S, simulated_clock: bool = False,
                 hard_timeout_s: float | None = None, quantum_s: float = 0.01, start_timeout_s: float = 60.0,
                 close_timeout_s: float = 5.0, latency_s: float | None = None):
        """Start and configure a worker per named plug-in (in parallel); a plug-in that fails to load or to
        configure raises PluginError here, after the other workers have been stopped."""
        self.emit = emit
        self.budget_s = budget_s
        if hard_timeout_s is None:
            hard_timeout_s = max(3.0 * budget_s, SIMULATED_HARD_TIMEOUT_S) if simulated_clock else budget_s
        self.timing = Timing(simulated_clock, budget_s, hard_timeout_s, quantum_s=quantum_s,
                             start_timeout_s=start_timeout_s, latency_s=latency_s)
        self.close_timeout_s = close_timeout_s
        self.names: dict[str, str] = {}
        self.workers: dict[str, RoleWorker] = {}
        self.now = -math.inf  # the latest vehicle time the host was given
        self.closed = False
        try:
            for role, name in roles.items():
                if name is not None:
                    self.workers[role] = RoleWorker(role, name, settings, self.timing)
                    self.names[role] = name
            deadline = time.monotonic() + start_timeout_s
            for worker in self.workers.values():
                worker.wait_ready(deadline)
        except BaseException:
            self.close()
            raise

    @property
    def simulated_clock(self) -> bool:
        return self.timing.simulated

    def has(self, role: str) -> bool:
        return role in self.workers

    def stats(self) -> dict[str, dict[str, Any]]:
        """Per role: the plug-in, its calls answered, its faults, and the CPU time its calls took (measured in
        the worker; in simulation, compare with the latency charged)."""
        out: dict[str, dict[str, Any]] = {}
        for role, worker in self.workers.items():
            cpu = sorted(worker.cpu_s)
            out[role] = {"plugin": self.names[role], "calls": len(cpu), "faults": worker.fault_count,
                         "cpu_ms_median": round(1e3 * cpu[len(cpu) // 2], 1) if cpu else None,
                         "cpu_ms_max": round(1e3 * cpu[-1], 1) if cpu else None,
                         "charged_ms": None if self.timing.latency_s is None or not self.timing.simulated
                         else round(1e3 * self.timing.latency_s, 1)}
        return out

    def submit(self, role: str, frame: StereoImages, request: Any, now: float) -> PluginCall:
        """Hand a frame to a plug-in without waiting for it; `PluginCall.poll(now)` gives the result once it is
        ready (tagged with `frame.time`: the agent uses it at that time, with the navigation estimate then)."""
        self._advance(now)
        call = PluginCall(role, frame.time)
        call.submitted_at = now
        worker = self.workers.get(role)
        if worker is None or self.closed:
            why = f"no '{role}' plug-in configured" if worker is None else "the plug-in host was closed"
            call.resolve(no_answer(role, why), now)
            return call
        call._waiter = self._poll
        worker.submit(call, frame, request)
        self._pump_all()
        return call

    def process(self, role: str, frame: StereoImages, request: Any, now: float) -> Any:
        """Call a plug-in and wait for its answer (at most the hard timeout); a fault gives "no answer"."""
        call = self.submit(role, frame, request, now)
        worker = self.workers.get(role)
        while worker is not None and not call.answered:
            worker.pump(self._wait_s(worker))
        self._flush(math.inf if self.simulated_clock else now)
        return call._result

    def _poll(self, call: PluginCall, now: float) -> Any | None:
        self._advance(now)
        self._pump_all()
        worker = self.workers.get(call.role)
        if self.simulated_clock and worker is not None:
            while not call.answered and now >= worker.lower_bound(call):
                worker.pump(self._wait_s(worker))  # the simulator waits: the onboard computer would be thinking
        self._flush(now)
        return call._result if call.answered and now >= call.ready_at else None

    def reset(self) -> None:
        """Between route elements: each plug-in drops its per-element state (queued behind submitted calls)."""
        for worker in self.workers.values():
            worker.reset()
        self._pump_all()

    def close(self) -> None:
        """Close every plug-in and stop its worker (killing it after `close_timeout_s`); idempotent."""
        if self.closed:
            return
        self.closed = True
        deadline = time.monotonic() + self.close_timeout_s
        for worker in self.workers.values():
            worker.close(deadline)
        self._flush(math.inf)

    def _advance(self, now: float) -> None:
        self.now = max(self.now, now)

    def _wait_s(self, worker: RoleWorker) -> float:
        return min(0.5, max(0.0, worker.next_deadline() - time.monotonic()) + 0.01)

    def _pump_all(self) -> None:
        if self.closed:
            return
        for worker in self.workers.values():
            worker.pump()
        self._flush(self.now)

    def _flush(self, until: float) -> None:
        """Emit the faults noticed so far: onboard at once (at the latest vehicle time); in simulation those due
        by `until`, at their simulated time."""
        due = []
        for worker in self.workers.values():
            keep = []
            for fault in worker.faults:
                if fault.due is None or fault.due <= until:
                    due.append((self.now if fault.due is None else fault.due, fault.fields))
                else:
                    keep.append(fault)
            worker.faults = keep
        for t, fields in sorted(due, key=lambda f: f[0]):
            self.emit("plugin_fault", t if math.isfinite(t) else 0.0, **fields)
