"""foxglove-sdk's own log lines, as formatted node log lines: joins, leaves and errors.

foxglove-sdk 0.30.3 has no Python callback for a client connecting or leaving (its
``ServerListener`` hears subscriptions only), and by default its Rust ``log`` output goes to
stderr unformatted, e.g. ``WebSocket protocol error: Connection reset without closing
handshake`` for a killed browser tab. ``foxglove._foxglove_py.enable_logging`` forwards that
output to Python's ``logging`` instead (loggers ``foxglove.<rust module>``), but only when
called before the process starts its first Foxglove sink, and only once per process.
``capture_sdk_log`` does that; ``SdkLogHandler`` turns the records into one line each:

- ``Registered client ADDR`` (foxglove.websocket.server): ``Foxglove client ADDR joined``;
- ``Error receiving from client ADDR: DETAIL`` (...connected_client.poller, ERROR): held,
  and given in that client's leave line, so a dropped connection is one line;
- ``Unregistered client ADDR``: ``Foxglove client ADDR left[: connection dropped (DETAIL)];
  the run goes on``, for every client, subscribed or not;
- other warnings and errors: ``Foxglove server: MESSAGE``; the rest at debug level.
"""

from __future__ import annotations

import logging
import re
import threading
from collections.abc import Callable

#: Python logger that foxglove-sdk's Rust log records arrive on (``foxglove.websocket...``).
SDK_LOGGER = 'foxglove'
_REGISTERED = re.compile(r'^Registered client (?P<client>\S+)$')
_UNREGISTERED = re.compile(r'^Unregistered client (?P<client>\S+)$')
_RECEIVE_ERROR = re.compile(r'^Error receiving from client (?P<client>\S+?): (?P<detail>.+)$')
#: Records the node states in its own words (its start-up line) or that the leave line covers.
_COVERED = (re.compile(r'^Started server on '), re.compile(r'^Connection closed by client '))

#: A log call of the node: (level, message), level one of logging's.
LogLine = Callable[[int, str], None]

_capture_lock = threading.Lock()
_captured = False


def capture_sdk_log(level: int = logging.INFO) -> None:
    """Send foxglove-sdk's log to Python's ``logging`` from now on (once per process).

    Call before the process's first Foxglove server: the SDK takes the first call only, and
    none after a sink started. The SDK would call ``logging.basicConfig`` on an unconfigured
    root logger (a stderr handler for every library's log); a placeholder handler on the
    root during the call prevents that. The ``foxglove`` logger keeps its records to itself.
    """
    global _captured
    with _capture_lock:
        if _captured:
            return
        from foxglove import _foxglove_py

        sdk = logging.getLogger(SDK_LOGGER)
        sdk.setLevel(level)
        sdk.propagate = False
        root = logging.getLogger()
        placeholder = logging.NullHandler()
        root.addHandler(placeholder)
        try:
            _foxglove_py.enable_logging(level)
        finally:
            root.removeHandler(placeholder)
        _captured = True


class SdkLogHandler(logging.Handler):
    """Turns foxglove-sdk's log records into one formatted node log line each (module doc)."""

    def __init__(self, log: LogLine) -> None:
        super().__init__(logging.DEBUG)
        self._log = log
        self._lock = threading.Lock()
        self._dropped: dict[str, str] = {}
        self._connected: set[str] = set()

    @property
    def connected(self) -> int:
        """Clients connected now, subscribed or not."""
        with self._lock:
            return len(self._connected)

    def emit(self, record: logging.LogRecord) -> None:
        """One record of the SDK: a join, a leave, a held error, or a plain line."""
        try:
            message = record.getMessage()
        except (TypeError, ValueError):
            message = str(record.msg)
        if match := _REGISTERED.match(message):
            with self._lock:
                self._connected.add(match['client'])
            self._log(logging.INFO, f'Foxglove client {match["client"]} joined')
        elif match := _RECEIVE_ERROR.match(message):
            with self._lock:
                self._dropped.setdefault(match['client'], match['detail'])
        elif match := _UNREGISTERED.match(message):
            with self._lock:
                self._connected.discard(match['client'])
                detail = self._dropped.pop(match['client'], None)
            why = '' if detail is None else f': connection dropped ({detail})'
            self._log(logging.INFO,
                      f'Foxglove client {match["client"]} left{why}; the run goes on')
        elif record.levelno >= logging.WARNING:
            self._log(record.levelno, f'Foxglove server: {message}')
        elif not any(pattern.match(message) for pattern in _COVERED):
            self._log(logging.DEBUG, f'Foxglove server: {message}')
