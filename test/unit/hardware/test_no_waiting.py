"""The ``no_waiting`` fixture (conftest.py) catches each way of waiting, on its thread only."""

from __future__ import annotations

import select
import socket
import threading
import time
from typing import Any

import pytest


def test_each_way_to_wait_raises_and_a_poll_does_not(no_waiting: Any) -> None:
    """sleep, select with a timeout, a blocking receive raise; their zero-time forms do not."""
    left, right = socket.socketpair()
    with left, right:
        right.sendall(b'x')
        with no_waiting.check():
            with pytest.raises(AssertionError, match=r'time\.sleep'):
                time.sleep(0.001)
            with pytest.raises(AssertionError, match=r'select\.select'):
                select.select([left], [], [], 0.01)
            with pytest.raises(AssertionError, match=r'socket\.recv on a blocking socket'):
                left.recv(1)
            time.sleep(0.0)
            assert select.select([left], [], [], 0.0)[0] == [left]
            left.setblocking(False)
            assert left.recv(1) == b'x'
        left.setblocking(True)
        right.sendall(b'y')
        assert left.recv(1) == b'y'  # outside the check: allowed


def test_other_threads_may_wait(no_waiting: Any) -> None:
    """A reader thread's sleep is its own business while the test's thread is checked."""
    slept = []
    with no_waiting.check():
        reader = threading.Thread(target=lambda: slept.append(time.sleep(0.01)))
        reader.start()
        reader.join()
    assert slept == [None]
