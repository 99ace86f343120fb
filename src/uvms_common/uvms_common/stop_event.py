"""SIGINT/SIGTERM as an event to poll, importable before anything heavy (no rclpy here).

A process installs its ``StopEvent`` first, so that a signal during its imports (rclpy,
numpy and Pinocchio take most of a second) stops it cleanly instead of raising
``KeyboardInterrupt`` with a traceback from whatever module was loading.

A process started by ``uvms launch`` starts with SIGINT blocked (``STOP_SIGNALS_BLOCKED``,
set between fork and exec by ``uvms_bringup.processes``): a stop that arrives while its
interpreter is still starting (the ROS wheels' ``.pth`` re-executes Python then) waits
pending instead of failing the start with ``Fatal Python error: init_import_site``. The
first ``StopEvent`` unblocks it once its handlers are installed, so the pending stop is
delivered to them at once and ends the process cleanly.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from types import FrameType

_active: list[StopEvent] = []

#: The signals a launched process starts with blocked, until its handlers are installed.
STOP_SIGNALS_BLOCKED = frozenset({signal.SIGINT})


def unblock_stop_signals() -> None:
    """Deliver the stop signals that were held while the process started (main thread)."""
    if hasattr(signal, 'pthread_sigmask'):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, STOP_SIGNALS_BLOCKED)


class StopEvent:
    """Set by SIGINT or SIGTERM; restores the previous handlers on ``restore``."""

    def __init__(self) -> None:
        self._event = threading.Event()
        self._previous: dict[int, object] = {}
        self._end: Callable[[], None] | None = None
        self.signal_number = 0
        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGINT, signal.SIGTERM):
                self._previous[sig] = signal.signal(sig, self._on_signal)
            _active.append(self)
            unblock_stop_signals()

    def _on_signal(self, signum: int, frame: FrameType | None) -> None:
        self.signal_number = signum
        self._event.set()
        if self._end is not None:
            self._end()

    @contextmanager
    def ending(self, end: Callable[[], None]) -> Iterator[None]:
        """Within the block a stop signal calls ``end``, which ends the process (``os._exit``).

        For start-up work that changes nothing outside the process (a node's build: its
        model, kernels and entities, seconds on a loaded machine), where nothing is lost by
        leaving at once and an exception raised into it (LLVM callbacks) would leave
        tracebacks; a stop that arrived before the block ends it at its start.
        """
        self._end = end
        try:
            if self._event.is_set():
                end()
            yield
        finally:
            self._end = None

    def defer_end(self) -> None:
        """From now on a stop only sets the event: the process changed what it must put back."""
        self._end = None

    def is_set(self) -> bool:
        """Whether a stop signal arrived."""
        return self._event.is_set()

    def set(self) -> None:
        """Ask the loop to stop (as a signal would)."""
        self._event.set()

    def restore(self) -> None:
        """Put the handlers back that were installed before."""
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)  # type: ignore[arg-type]
        self._previous.clear()
        if self in _active:
            _active.remove(self)


def active_stop_event() -> StopEvent | None:
    """The StopEvent whose handlers are installed in this process now, if any."""
    return _active[-1] if _active else None


def defer_stop_end() -> None:
    """Say that this process is about to change a device: a stop must not end it at once.

    A node's build may end at once on a stop (``StopEvent.ending``); a bridge whose
    activation starts changing its device calls this first, so that a stop from then on
    waits for the build and the node's own end, which puts the device back.
    """
    stop = active_stop_event()
    if stop is not None:
        stop.defer_end()
