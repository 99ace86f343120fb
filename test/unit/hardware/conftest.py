"""Fixtures shared by the hardware unit tests: ``no_waiting``, the proof that a call never waits.

A device's read() and write() run inside the robot's loop: they must never wait for the
device. Timing them proves little (a busy CI machine took 23 ms for 20 calls that wait for
nothing), so the fixture checks the cause instead. Inside ``no_waiting.check()``, on the
test's own thread, each way our code could wait raises ``WaitedError``:

- ``time.sleep`` for a positive time;
- ``select.select`` with a timeout other than 0 (None waits for ever);
- a receive or accept on a socket that blocks (its timeout is not 0).

Other threads (a twin's server, a link's reader) are left alone.
"""

from __future__ import annotations

import contextlib
import select
import socket
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest


class WaitedError(AssertionError):
    """A call that must never wait asked to."""


class NoWaiting:
    """Makes ``time.sleep``, ``select.select`` and blocking socket receives raise, per thread."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch) -> None:
        self._thread: int | None = None
        sleep, choose = time.sleep, select.select

        def checked_sleep(seconds: float) -> None:
            if seconds > 0.0 and self._checking():
                raise WaitedError(f'time.sleep({seconds})')
            sleep(seconds)

        def checked_select(rlist: Any, wlist: Any, xlist: Any,
                           timeout: float | None = None) -> Any:
            if (timeout is None or timeout > 0.0) and self._checking():
                raise WaitedError(f'select.select(timeout={timeout})')
            return choose(rlist, wlist, xlist, timeout)

        monkeypatch.setattr(time, 'sleep', checked_sleep)
        monkeypatch.setattr(select, 'select', checked_select)
        for name in ('recv', 'recvfrom', 'recv_into', 'recvfrom_into', 'accept'):
            monkeypatch.setattr(socket.socket, name,
                                self._nonblocking_only(name, getattr(socket.socket, name)))

    def _checking(self) -> bool:
        return self._thread == threading.get_ident()

    def _nonblocking_only(self, name: str, method: Callable[..., Any]) -> Callable[..., Any]:
        def checked(sock: socket.socket, *args: Any, **kwargs: Any) -> Any:
            if self._checking() and sock.gettimeout() != 0.0:
                raise WaitedError(f'socket.{name} on a blocking socket '
                                  f'(timeout {sock.gettimeout()})')
            return method(sock, *args, **kwargs)
        return checked

    @contextlib.contextmanager
    def check(self) -> Iterator[None]:
        """Within: any wait on this thread raises ``WaitedError``."""
        self._thread = threading.get_ident()
        try:
            yield
        finally:
            self._thread = None


@pytest.fixture
def no_waiting(monkeypatch: pytest.MonkeyPatch) -> NoWaiting:
    """``with no_waiting.check():`` fails the test on any wait of the test's thread."""
    return NoWaiting(monkeypatch)

