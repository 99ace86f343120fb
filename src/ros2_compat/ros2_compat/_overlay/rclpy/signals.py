"""SIGINT/SIGTERM handling as rclpy installs it: shut every context down, then chain."""

from __future__ import annotations

import signal
import threading
from enum import IntEnum
from types import FrameType
from typing import Any


class SignalHandlerOptions(IntEnum):
    """Which signal handlers rclpy.init installs."""

    NO = 0
    SIGINT = 1
    SIGTERM = 2
    ALL = 3


_installed: dict[int, Any] = {}
_options = SignalHandlerOptions.NO


def _handler(signum: int, frame: FrameType | None) -> None:
    from rclpy.context import _live_contexts

    for context in list(_live_contexts):
        context.try_shutdown()
    previous = _installed.get(signum)
    if callable(previous):
        previous(signum, frame)


def install_signal_handlers(options: SignalHandlerOptions = SignalHandlerOptions.ALL) -> None:
    """Install handlers that shut all contexts down on SIGINT and/or SIGTERM.

    After the shutdown, SIGINT still reaches Python's own handler (KeyboardInterrupt); spinning
    executors see the shutdown and raise ExternalShutdownException. Only the main thread can
    install handlers; elsewhere this does nothing.
    """
    global _options
    if threading.current_thread() is not threading.main_thread():
        return
    wanted = []
    if options in (SignalHandlerOptions.SIGINT, SignalHandlerOptions.ALL):
        wanted.append(signal.SIGINT)
    if options in (SignalHandlerOptions.SIGTERM, SignalHandlerOptions.ALL):
        wanted.append(signal.SIGTERM)
    for signum in wanted:
        if signum not in _installed:
            _installed[signum] = signal.getsignal(signum)
            signal.signal(signum, _handler)
    _options = SignalHandlerOptions(options) if wanted else _options


def get_current_signal_handlers_options() -> SignalHandlerOptions:
    """Return which handlers are installed."""
    return _options


def uninstall_signal_handlers() -> None:
    """Restore the signal handlers that were in place before rclpy installed its own."""
    global _options
    if threading.current_thread() is not threading.main_thread():
        return
    for signum, previous in list(_installed.items()):
        if signal.getsignal(signum) is _handler:
            signal.signal(signum, previous if previous is not None else signal.SIG_DFL)
        del _installed[signum]
    _options = SignalHandlerOptions.NO
