"""Plug-ins run in worker processes: hangs, crashes and exceptions are faults the host survives, results come back
in order and tagged with their frame's time, and the simulated clock is charged each call's CPU time.

Every test runs real worker processes (`mission.testing_plugins`), bounded in wall time.
"""

from __future__ import annotations

import multiprocessing
import time
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest

from mission.errors import PluginError
from mission.plugin_api import ReferencingResult, StereoImages
from mission.plugin_calls import RESTART_CHARGE_S, PluginCall
from mission.plugin_host import PluginHost
from mission.plugins import load_plugin
from mission.testing_plugins import FAULT, EchoPlugin

TESTING = "mission.testing_plugins:"


def plugin_workers() -> list[multiprocessing.process.BaseProcess]:
    """This process's live plug-in workers (other tests' process pools are not ours to count)."""
    return [p for p in multiprocessing.active_children() if p.name.startswith("auv-plugin:")]


def frame(t: float, shape: tuple[int, int] = (120, 160)) -> StereoImages:
    left = np.full(shape, round(10 * t) % 250, np.uint8)
    return StereoImages(t, left, left, np.array([[100.0, 0, 80], [0, 100, 60], [0, 0, 1]]), 0.25)


class Recorder:
    def __init__(self) -> None:
        self.events: list[tuple[str, float, dict[str, Any]]] = []

    def __call__(self, event: str, t: float, **fields: Any) -> None:
        self.events.append((event, t, fields))

    def faults(self) -> list[dict[str, Any]]:
        return [f for e, _, f in self.events if e == "plugin_fault"]


@pytest.fixture
def host_of() -> Iterator[Any]:
    """`host_of(plugin class name, **PluginHost options)` → (host, recorder); every host is closed at the end."""
    hosts: list[PluginHost] = []

    def make(name: str, settings: dict[str, Any] | None = None, **options: Any) -> tuple[PluginHost, Recorder]:
        recorder = Recorder()
        hosts.append(PluginHost({"referencing": TESTING + name}, settings or {}, recorder, **options))
        return hosts[-1], recorder

    yield make
    for host in hosts:
        host.close()
    assert plugin_workers() == []


def wait_for(call: PluginCall, now: float = 1e9, within_s: float = 20.0) -> Any:
    """Poll (never blocking onboard) until the result is ready; fails the test past `within_s` of wall time."""
    end = time.monotonic() + within_s
    while (result := call.poll(now)) is None:
        assert time.monotonic() < end, f"no result for the frame at {call.frame_time} within {within_s} s"
        time.sleep(0.01)
    return result


def test_load_plugin_takes_an_import_path_as_well_as_an_entry_point_name():
    assert load_plugin(TESTING + "EchoPlugin") is EchoPlugin
    assert load_plugin("stereo-vo").__name__ == "StereoOdometryPlugin"
    with pytest.raises(PluginError, match="'mission.testing_plugins:NoSuch' failed to load: AttributeError"):
        load_plugin(TESTING + "NoSuch")


def test_a_sleeping_plugins_call_is_abandoned_at_its_budget_and_the_restarted_worker_answers_the_next(host_of):
    host, recorder = host_of("SleepingPlugin", budget_s=1.0)
    t0 = time.monotonic()
    hung = host.submit("referencing", frame(1.0), FAULT, 1.0)
    after = host.submit("referencing", frame(1.2), None, 1.2)
    failed = wait_for(hung)
    abandoned_after = time.monotonic() - t0
    answer = wait_for(after)
    assert 1.0 <= abandoned_after < 1.0 + 0.5, "abandoned at the budget, not after the plug-in's 30 s"
    assert isinstance(failed, ReferencingResult) and not failed.recognised
    assert failed.details["worker_restarted"] is True
    [fault] = recorder.faults()
    assert fault["role"] == "referencing" and fault["frame_time"] == 1.0 and "no answer within 1 s" in fault["error"]
    assert fault["elapsed_ms"] >= 1000.0
    assert answer.recognised and answer.details["frame_time"] == 1.2 and answer.matched == 1  # a fresh plug-in
    assert time.monotonic() - t0 < 10.0


@pytest.mark.parametrize(("plugin", "how"), [("SegfaultingPlugin", "killed by SIGSEGV"),
                                             ("ExitingPlugin", "exited with code 3")])
def test_a_crashing_plugin_is_a_fault_and_its_worker_restarts(host_of, plugin, how):
    host, recorder = host_of(plugin, budget_s=2.0)
    before = wait_for(host.submit("referencing", frame(0.0), None, 0.0))
    crashed = host.submit("referencing", frame(0.5), FAULT, 0.5)
    queued = host.submit("referencing", frame(1.0), None, 1.0)
    assert not wait_for(crashed, within_s=5.0).recognised
    answer = wait_for(queued)
    [fault] = recorder.faults()
    assert fault["frame_time"] == 0.5 and how in fault["error"] and fault["worker_restarted"] is True
    assert answer.recognised and answer.details["frame_time"] == 1.0
    assert answer.details["pid"] != before.details["pid"]


def test_an_exception_is_a_fault_and_the_same_worker_answers_the_next_call(host_of):
    host, recorder = host_of("RaisingPlugin")
    first = wait_for(host.submit("referencing", frame(0.0), None, 0.0))
    failed = wait_for(host.submit("referencing", frame(0.5), FAULT, 0.5))
    after = wait_for(host.submit("referencing", frame(1.0), None, 1.0))
    assert not failed.recognised and "asked to fail" in failed.details["reason"]
    assert [f["error"] for f in recorder.faults()] == [
        "plug-in fault: RuntimeError('the test plug-in was asked to fail')"]
    assert after.details["pid"] == first.details["pid"] and after.matched == 3


def test_a_result_that_cannot_be_sent_back_is_a_fault(host_of):
    host, recorder = host_of("UnpicklableResultPlugin")
    failed = wait_for(host.submit("referencing", frame(0.0), FAULT, 0.0))
    after = wait_for(host.submit("referencing", frame(0.5), None, 0.5))
    assert not failed.recognised and "could not be sent back" in failed.details["reason"]
    assert len(recorder.faults()) == 1 and after.recognised


def test_a_worker_killed_while_idle_is_replaced_and_the_fault_logged(host_of):
    import os
    import signal

    host, recorder = host_of("EchoPlugin")
    before = wait_for(host.submit("referencing", frame(0.0), None, 0.0))
    os.kill(before.details["pid"], signal.SIGKILL)
    time.sleep(0.2)
    after = wait_for(host.submit("referencing", frame(1.0), None, 1.0))
    assert after.recognised and after.details["pid"] != before.details["pid"]
    [fault] = recorder.faults()
    assert "while idle" in fault["error"] and "SIGKILL" in fault["error"]


def test_a_worker_that_cannot_restart_breaks_its_role_with_one_fault(host_of, tmp_path):
    host, recorder = host_of("StartsOncePlugin", {"marker": str(tmp_path / "configured")})
    crashed = host.submit("referencing", frame(0.0), FAULT, 0.0)
    queued = host.submit("referencing", frame(0.5), None, 0.5)
    assert not wait_for(crashed).recognised
    assert "plug-in unavailable: restart failed" in wait_for(queued).details["reason"]
    later = host.submit("referencing", frame(1.0), None, 1.0)
    assert later.poll(1.0) is not None and not later.poll(1.0).recognised  # at once, without a worker
    errors = [f["error"] for f in recorder.faults()]
    assert len(errors) == 2 and "SIGSEGV" in errors[0] and "configured once already" in errors[1]


def test_results_come_back_in_submission_order_tagged_with_their_frame_time(host_of):
    host, recorder = host_of("SlowPlugin", {"cpu_s": 0.02})
    calls = [host.submit("referencing", frame(0.1 * k, (480, 640)), None, 0.1 * k) for k in range(12)]
    order: list[int] = []
    end = time.monotonic() + 20.0
    while len(order) < len(calls) and time.monotonic() < end:
        for k in reversed(range(len(calls))):  # look at the late ones first: none may overtake an earlier one
            if k not in order and calls[k].poll(1e9) is not None:
                order.append(k)
        time.sleep(0.005)
    assert order == list(range(12))
    results = [c.poll(1e9) for c in calls]
    assert [r.details["frame_time"] for r in results] == [c.frame_time for c in calls]
    assert [r.matched for r in results] == list(range(1, 13))
    assert [r.details["left_mean"] for r in results] == [float(int(k) % 250) for k in range(12)]
    assert recorder.faults() == []


def test_a_2_mb_stereo_pair_goes_to_the_worker_and_back_in_a_small_part_of_a_control_tick(host_of):
    """Frames are pickled through a pipe (about 2 ms per MB here); a 5 Hz tick is 200 ms."""
    host, _ = host_of("EchoPlugin")
    big = frame(0.0, (900, 1200))
    wait_for(host.submit("referencing", big, None, 0.0))
    round_trips, submits = [], []
    for k in range(10):
        t0 = time.perf_counter()
        call = host.submit("referencing", big, None, float(k))
        submits.append(time.perf_counter() - t0)
        wait_for(call)
        round_trips.append(time.perf_counter() - t0)
    assert float(np.median(round_trips)) < 0.05
    assert float(np.median(submits)) < 0.005  # the caller's share: queuing, not pickling or writing


def test_reset_reaches_the_worker_behind_the_calls_already_submitted(host_of):
    host, _ = host_of("EchoPlugin")
    first = [host.submit("referencing", frame(t), None, t) for t in (0.0, 0.1)]
    host.reset()
    later = host.submit("referencing", frame(0.2), None, 0.2)
    assert [wait_for(c).matched for c in first] == [1, 2]
    assert wait_for(later).matched == 1


def test_in_simulated_time_a_result_is_ready_after_the_calls_cpu_time_and_not_before(host_of):
    host, recorder = host_of("SlowPlugin", {"cpu_s": 0.2}, simulated_clock=True)
    first = host.submit("referencing", frame(10.0), None, 10.0)
    second = host.submit("referencing", frame(10.0), None, 10.0)  # queued behind the first: the worker is busy
    assert first.poll(10.005) is None  # before any latency could have passed: no waiting for the worker
    assert first.poll(10.1) is None  # the worker has answered, but its 0.2 s of CPU are not over
    assert 10.2 <= first.ready_at <= 10.2 + 0.1
    assert first.poll(first.ready_at).recognised
    assert second.poll(first.ready_at + 0.1) is None
    assert 0.2 <= second.ready_at - first.ready_at <= 0.3
    assert second.poll(second.ready_at).recognised
    assert recorder.faults() == []


def test_in_simulated_time_the_budget_counts_cpu_time_so_a_slow_machine_is_no_fault(host_of):
    """A plug-in that waits 1.5 s of wall time with no CPU (a loaded machine, as far as the call can tell) is
    within a 1 s budget in simulation, and its result is ready a few quanta after submission (the call's own CPU:
    unpickling the frame, which a loaded machine stretches)."""
    host, recorder = host_of("SleepingPlugin", {"sleep_s": 1.5}, simulated_clock=True, budget_s=1.0)
    call = host.submit("referencing", frame(3.0), FAULT, 3.0)
    result = call.poll(3.5)
    assert result is not None and result.recognised
    assert 3.0 < call.ready_at <= 3.3  # its own CPU (tens of ms on a loaded machine), never the 1.5 s of sleep
    assert recorder.faults() == []


def test_in_simulated_time_a_call_over_its_cpu_budget_is_a_fault_charged_the_budget(host_of):
    host, recorder = host_of("SlowPlugin", {"cpu_s": 0.3}, simulated_clock=True, budget_s=0.1)
    call = host.submit("referencing", frame(5.0), None, 5.0)
    assert call.poll(5.05) is None
    assert call.ready_at == pytest.approx(5.1)
    assert recorder.faults() == []  # the worker has answered, but the fault is emitted at its simulated time
    result = call.poll(5.1)
    assert not result.recognised and "over its time budget" in result.details["reason"]
    [(event, t, fields)] = recorder.events
    assert t == pytest.approx(5.1) and fields["frame_time"] == 5.0


def test_in_simulated_time_a_crash_is_charged_a_quantum_and_the_restart_its_start_up_time(host_of):
    host, recorder = host_of("SegfaultingPlugin", simulated_clock=True)
    crashed = host.submit("referencing", frame(2.0), FAULT, 2.0)
    queued = host.submit("referencing", frame(2.0), None, 2.0)
    assert not crashed.poll(2.01).recognised and crashed.ready_at == pytest.approx(2.01)
    assert queued.poll(2.05) is None
    assert queued.poll(10.0).recognised
    assert 2.01 + 0.1 <= queued.ready_at - 0.01 < 2.01 + 3.0  # the fresh interpreter's CPU time, in 0.1 s steps
    assert queued.poll(queued.ready_at - 0.005) is None
    assert [t for e, t, _ in recorder.events] == [pytest.approx(2.01)]


def test_with_a_modelled_latency_every_call_is_ready_exactly_that_latency_after_it_could_start(host_of):
    """The simulator's default: whatever the call's CPU time (0.3 s here, and a loaded machine's), a result is
    ready a fixed latency after the worker could take it, so a run repeats exactly for its seed."""
    host, recorder = host_of("SlowPlugin", {"cpu_s": 0.3}, simulated_clock=True, latency_s=0.1)
    first = host.submit("referencing", frame(4.0), None, 4.0)
    second = host.submit("referencing", frame(4.0), None, 4.0)
    assert first.poll(4.09) is None
    assert first.poll(4.1).recognised and first.ready_at == pytest.approx(4.1, abs=1e-12)
    assert second.poll(4.15) is None
    assert second.poll(4.2).recognised and second.ready_at == pytest.approx(4.2, abs=1e-12)
    [stats] = host.stats().values()
    assert stats["calls"] == 2 and stats["charged_ms"] == 100.0 and stats["cpu_ms_median"] >= 290.0
    assert recorder.faults() == []


def test_with_a_modelled_latency_a_crash_costs_a_quantum_and_the_restart_a_fixed_time(host_of):
    host, recorder = host_of("SegfaultingPlugin", simulated_clock=True, latency_s=0.1)
    crashed = host.submit("referencing", frame(2.0), FAULT, 2.0)
    queued = host.submit("referencing", frame(2.0), None, 2.0)
    assert not crashed.poll(2.01).recognised and crashed.ready_at == pytest.approx(2.01)
    assert queued.poll(10.0).recognised
    assert queued.ready_at == pytest.approx(2.01 + RESTART_CHARGE_S + 0.1, abs=1e-9)


def test_in_simulated_time_the_hard_timeout_counts_the_workers_cpu_so_only_a_spinning_call_is_killed(host_of):
    """A call that waits 2 s of wall time without CPU (what a loaded machine looks like) outlives a 0.5 s hard
    timeout; one that spins its CPU is abandoned at it, charged its budget, and its worker restarted."""
    host, recorder = host_of("SleepingPlugin", {"sleep_s": 2.0}, simulated_clock=True, budget_s=0.2,
                             hard_timeout_s=0.5)
    assert wait_for(host.submit("referencing", frame(1.0), FAULT, 1.0)).recognised
    assert recorder.faults() == []
    host, recorder = host_of("SlowPlugin", {"cpu_s": 30.0}, simulated_clock=True, budget_s=0.2, hard_timeout_s=0.5)
    started = time.monotonic()
    result = wait_for(host.submit("referencing", frame(1.0), None, 1.0))
    assert not result.recognised and "of CPU time" in result.details["reason"]
    assert time.monotonic() - started < 20.0 and result.details["worker_restarted"]


def test_a_plugin_that_fails_to_configure_is_a_plugin_error_at_construction():
    with pytest.raises(PluginError, match="failed to start: ValueError\\('this plug-in never starts'\\)"):
        PluginHost({"referencing": TESTING + "BrokenPlugin"}, {}, Recorder())
    assert plugin_workers() == []


def test_a_plugin_that_is_not_installed_is_a_plugin_error_naming_the_installed_ones():
    with pytest.raises(PluginError, match="'no-such-vo' is not installed \\(installed: .*stereo-vo"):
        PluginHost({"odometry": "no-such-vo"}, {}, Recorder())
    assert plugin_workers() == []


def test_close_stops_a_hung_worker_and_leaves_no_child_process():
    host = PluginHost({"referencing": TESTING + "SleepingPlugin", "odometry": TESTING + "EchoPlugin"}, {},
                      Recorder(), close_timeout_s=1.0)
    hung = host.submit("referencing", frame(0.0), FAULT, 0.0)
    time.sleep(0.2)
    t0 = time.monotonic()
    host.close()
    assert time.monotonic() - t0 < 1.0 + 1.0
    assert plugin_workers() == []
    assert not hung.poll(1.0).recognised  # "the plug-in host was closed"
    assert not host.submit("odometry", frame(1.0), None, 1.0).poll(1.0).ok
    assert plugin_workers() == []  # and nothing restarted them
