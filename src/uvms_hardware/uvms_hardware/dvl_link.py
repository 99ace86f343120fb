"""The dvl_bridge's TCP side, without ROS: connect, read, parse, reconnect, in a thread.

The thread connects to the DVL (``HOST:PORT``), feeds what it reads to a `DvlParser` and
queues the velocity reports with the time (s) of their arrival, read on ``arrival_clock`` (the
clock the bridge stamps with, for `uvms_hardware.device_time`) as soon as ``recv`` returns, not
when the node drains the queue; ``clock`` (steady) times the reports' age. A closed or failed
connection is retried every ``reconnect_period_s``. The node drains `take` from its timer::

    link = DvlLink(parse_host_port('127.0.0.1', 16171)).start()
    for t_s, report in link.take(): ...
    link.stop()
"""

from __future__ import annotations

import socket
import threading
import time
from collections import deque
from collections.abc import Callable

from uvms_hardware.address import HostPort
from uvms_hardware.dvl_protocol import DvlParser, VelocityReport


class DvlLink:
    """A reader thread on one DVL; counters for /diagnostics."""

    def __init__(self, address: HostPort, reconnect_period_s: float = 1.0,
                 clock: Callable[[], float] = time.monotonic,
                 arrival_clock: Callable[[], float] | None = None) -> None:
        self.address = address
        self.reconnect_period_s = reconnect_period_s
        self.clock = clock
        self.arrival_clock = clock if arrival_clock is None else arrival_clock
        self.parser = DvlParser()
        self.connected = False
        self.connects = 0
        self.last_error = ''
        self.last_report_s = -float('inf')
        self.last_valid: bool | None = None
        self._queue: deque[tuple[float, VelocityReport]] = deque(maxlen=1000)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name='dvl link', daemon=True)

    def start(self) -> DvlLink:
        """Start the reader thread; returns self."""
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop the thread (within one read timeout) and close the connection."""
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=2.0)

    def wait_connected(self, timeout_s: float) -> bool:
        """True once connected within ``timeout_s``."""
        end_s = time.monotonic() + timeout_s
        while not self.connected and time.monotonic() < end_s:
            time.sleep(0.01)
        return self.connected

    def take(self) -> list[tuple[float, VelocityReport]]:
        """Reports queued since the last call, oldest first, with their arrival (s)."""
        out = []
        while self._queue:
            out.append(self._queue.popleft())
        return out

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                with socket.create_connection(self.address, timeout=1.0) as sock:
                    sock.settimeout(0.1)
                    self.connected = True
                    self.connects += 1
                    self._read(sock)
            except OSError as exc:
                self.last_error = f'{self.address.host}:{self.address.port}: {exc}'
            self.connected = False
            self._stop.wait(self.reconnect_period_s)

    def _read(self, sock: socket.socket) -> None:
        partial = DvlParser()  # a fresh line buffer per connection, counters merged below
        while not self._stop.is_set():
            try:
                data = sock.recv(65536)
            except TimeoutError:
                continue
            arrival_s = self.arrival_clock()
            if not data:
                self.last_error = 'the DVL closed the connection'
                return
            before = (partial.malformed, partial.ignored, partial.reports)
            reports = partial.feed(data)
            self.parser.malformed += partial.malformed - before[0]
            self.parser.ignored += partial.ignored - before[1]
            self.parser.reports += partial.reports - before[2]
            self.parser.last_error = partial.last_error or self.parser.last_error
            now_s = self.clock()
            for report in reports:
                self.last_report_s = now_s
                self.last_valid = report.valid
                self._queue.append((arrival_s, report))
