"""SIGINT and SIGTERM during a run (`auv simulate`, `auv run`): the first asks the run to stop cleanly, a second
(or one that arrives while no executive is running) interrupts at once with `Interrupted`.

The exit codes follow the shell's convention, 128 + the signal's number: 130 for SIGINT, 143 for SIGTERM.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from types import FrameType

from mission.errors import AuvError

StopFn = Callable[[str], None]


class Interrupted(AuvError):
    """A run ended by a signal before it could stop cleanly."""

    def __init__(self, signum: int):
        self.signum = signum
        super().__init__(f"interrupted by {signal.Signals(signum).name}")

    @property
    def exit_code(self) -> int:
        return 128 + self.signum


def exit_code(signum: int) -> int:
    """The process exit code of a run ended by `signum` (130 for SIGINT, 143 for SIGTERM)."""
    return 128 + signum


class SignalStop:
    """What a run's signal handler knows: the first signal received (`signum`) and whom to ask to stop (`target`,
    e.g. `Executive.request_stop`; while it is None a signal interrupts at once)."""

    def __init__(self, target: StopFn | None = None):
        self.target = target
        self.signum: int | None = None
        self.closing = False  # while the run writes its end, signals are noted, not acted on

    @property
    def reason(self) -> str:
        return f"stopped by {signal.Signals(self.signum).name}" if self.signum is not None else ""

    def handle(self, signum: int, frame: FrameType | None) -> None:
        first = self.signum is None
        if first:
            self.signum = signum
        if self.closing:
            return
        if first and self.target is not None:
            self.target(self.reason)
            return
        raise Interrupted(self.signum if self.signum is not None else signum)


@contextmanager
def stop_on_signals(target: StopFn | None = None, install: bool = True) -> Iterator[SignalStop]:
    """Handle SIGINT and SIGTERM with a `SignalStop` for the duration of the block (only in the main thread,
    where Python delivers signals; elsewhere, or with `install` false, nothing is installed)."""
    stop = SignalStop(target)
    if not install or threading.current_thread() is not threading.main_thread():
        yield stop
        return
    previous = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    for s in previous:
        signal.signal(s, stop.handle)
    try:
        yield stop
    finally:
        for s, h in previous.items():
            signal.signal(s, h)


def signal_name(signum: int) -> str:
    return signal.Signals(signum).name
