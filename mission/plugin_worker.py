"""One perception plug-in in its own process, out of the control loop (issue 19, item 4).

`serve` is the worker's main: it loads the plug-in by the same spec the host was given (an entry-point name or
a `module:Class` path, `mission.plugins.load_plugin`), configures it once, then answers the messages it reads,
in order:

- `("configure", settings)` first → `("ready", cpu_s)` (the worker's CPU time so far) or `("start_failed", why)`;
- `("process", seq, frame, request)` → `("answer", seq, result, cpu_s, wall_s)` or
  `("raised", seq, error, cpu_s, wall_s)`; `cpu_s` is the call's `time.process_time` in the worker (what a
  loaded machine does not inflate), `wall_s` its `time.perf_counter`;
- `("reset",)` → `("reset", error or None)`; `("close",)` → `("closed", error or None)`, then the worker exits.

`WorkerProcess` is the host's handle on one incarnation of a worker: it starts it with the `spawn` context (a
fresh interpreter: the host's process may hold MuJoCo, OpenGL contexts and threads, which must never be forked),
sends messages through a feeder thread (a 1 MB stereo frame never blocks the control loop on a busy worker's
full pipe), and reads answers without blocking. Frames are pickled through the pipe: measured here, a round trip
costs about 2 ms per MB of stereo pair and `submit` 0.05 ms of the caller's time, so shared memory is not used.
A killed or crashed worker is replaced by a new incarnation; this class never restarts itself.
"""

from __future__ import annotations

import multiprocessing
import os
import pickle
import queue
import signal
import sys
import threading
import time
from multiprocessing.connection import Connection
from multiprocessing.process import BaseProcess
from typing import Any

from mission.errors import PluginError
from mission.plugin_api import PerceptionPlugin

Message = tuple[Any, ...]


def serve(spec: str, inbox: Connection, outbox: Connection) -> None:
    """The worker process's main (see the module docstring for the messages)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C reaches the whole process group; the host stops us
    _die_with_parent()
    try:
        kind, settings = inbox.recv()
        assert kind == "configure", kind
        plugin = _start(spec, settings)
    except Exception as exc:  # a plug-in that cannot start is reported, never a traceback on the console
        outbox.send(("start_failed", str(exc) if isinstance(exc, PluginError) else repr(exc)))
        return
    outbox.send(("ready", time.process_time()))
    while True:
        try:
            message = inbox.recv()
        except (EOFError, OSError):  # the host is gone
            return
        if message[0] == "process":
            _, seq, frame, request = message
            outbox_send(outbox, _call(plugin, seq, frame, request))
        elif message[0] == "reset":
            outbox.send(("reset", _guarded(plugin.reset)))
        elif message[0] == "close":
            outbox.send(("closed", _guarded(plugin.close)))
            return


def _start(spec: str, settings: Any) -> PerceptionPlugin:
    from mission.plugins import load_plugin

    factory = load_plugin(spec)
    try:
        instance = factory()
        instance.configure(settings)
    except Exception as exc:
        raise PluginError(f"perception plug-in '{spec}' failed to start: {exc!r}") from exc
    if not isinstance(instance, PerceptionPlugin):
        raise PluginError(f"perception plug-in '{spec}' does not implement configure/process/reset/close")
    return instance


def _call(plugin: PerceptionPlugin, seq: int, frame: Any, request: Any) -> Message:
    c0, w0 = time.process_time(), time.perf_counter()
    try:
        result = plugin.process(frame, request)
    except Exception as exc:
        return ("raised", seq, repr(exc), time.process_time() - c0, time.perf_counter() - w0)
    return ("answer", seq, result, time.process_time() - c0, time.perf_counter() - w0)


def outbox_send(outbox: Connection, message: Message) -> None:
    """Send an answer; a result that cannot be pickled is reported as the call's error instead."""
    try:
        outbox.send(message)
    except (pickle.PicklingError, TypeError, AttributeError, ValueError) as exc:  # an unpicklable result
        outbox.send(("raised", message[1], f"its result could not be sent back: {exc!r}", *message[3:]))


def _guarded(call: Any) -> str | None:
    try:
        call()
    except Exception as exc:
        return repr(exc)
    return None


def _die_with_parent() -> None:
    """Linux: have the kernel kill this worker when the host process dies (a `kill -9` of `auv run` must not
    leave a hung plug-in behind). Elsewhere the worker exits at its next read of the closed pipe."""
    if sys.platform.startswith("linux"):
        import ctypes

        try:
            ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
        except (OSError, AttributeError):
            pass


_CLOCK_TICKS = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100


class WorkerProcess:
    """One running incarnation of a plug-in's worker, seen from the host."""

    def __init__(self, spec: str, settings: Any):
        ctx = multiprocessing.get_context("spawn")
        inbox_read, self._inbox = ctx.Pipe(duplex=False)
        self._outbox, outbox_write = ctx.Pipe(duplex=False)
        self.process: BaseProcess = ctx.Process(target=serve, args=(spec, inbox_read, outbox_write),
                                                name=f"auv-plugin:{spec}", daemon=True)
        self.started_wall = time.monotonic()
        self.process.start()
        inbox_read.close()  # only the worker holds these ends: its death is EOF here and EPIPE for the feeder
        outbox_write.close()
        self._feed: queue.SimpleQueue[Message | None] = queue.SimpleQueue()
        self._feeder = threading.Thread(target=self._feed_loop, name=f"auv-plugin-feed:{spec}", daemon=True)
        self._feeder.start()
        self.ended = False  # EOF read: the worker is gone (after delivering everything it sent)
        self.send(("configure", settings))

    def _feed_loop(self) -> None:
        while (message := self._feed.get()) is not None:
            try:
                self._inbox.send(message)
            except (OSError, ValueError):  # the worker died (EPIPE) or was killed: its messages are void
                break
        self._inbox.close()

    def send(self, message: Message) -> None:
        """Queue a message for the worker; never blocks."""
        self._feed.put(message)

    def cpu_s(self) -> float | None:
        """The worker's CPU time so far (user + system, from /proc), or None where /proc cannot tell."""
        try:
            with open(f"/proc/{self.process.pid}/stat", encoding="ascii") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            return (int(fields[11]) + int(fields[12])) / _CLOCK_TICKS
        except (OSError, ValueError, IndexError):
            return None

    def receive(self, timeout: float = 0.0) -> list[Message]:
        """The messages the worker has sent so far, waiting up to `timeout` seconds for the first one."""
        out: list[Message] = []
        if self.ended:
            return out
        try:
            while self._outbox.poll(timeout if not out else 0.0):
                out.append(self._outbox.recv())
        except (EOFError, OSError):
            self.ended = True
        return out

    @property
    def pid(self) -> int | None:
        return self.process.pid

    def alive(self) -> bool:
        return not self.ended and self.process.is_alive()

    def exit_description(self) -> str:
        """How the worker ended, once its pipe has closed (it is then exiting: wait briefly to reap it)."""
        if self.process.exitcode is None:
            self.process.join(0.2)
        code = self.process.exitcode
        if code is None:
            return "its pipe closed"
        if code < 0:
            try:
                return f"killed by {signal.Signals(-code).name}"
            except ValueError:
                return f"killed by signal {-code}"
        return f"exited with code {code}"

    def kill(self) -> None:
        """Kill the worker now (SIGKILL) and stop feeding it; reaping is `join`'s business."""
        self._feed.put(None)
        if self.process.is_alive():
            self.process.kill()
        self.ended = True

    def stop(self, deadline: float) -> None:
        """Wait until the wall-clock `deadline` (`time.monotonic`) for the worker to exit, then kill it; reap it."""
        self._feed.put(None)
        self.process.join(max(0.0, deadline - time.monotonic()))
        if self.process.is_alive():
            self.process.kill()
            self.process.join(5.0)
        self._outbox.close()
        self.ended = True

    def reap(self) -> bool:
        """True once the (killed or exited) process has been reaped; never blocks."""
        self.process.join(0.0)
        if self.process.exitcode is None:
            return False
        self._outbox.close()
        return True
