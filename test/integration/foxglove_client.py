"""A minimal client of Foxglove's WebSocket protocol, as the Foxglove app speaks it, for tests.

Spoken over the ``websockets`` library: JSON text frames for ``serverInfo``, ``advertise``
and ``subscribe``; binary ``messageData`` frames (opcode 1, subscription id uint32 LE,
log time uint64 LE ns, then the payload) and ``time`` frames (opcode 2, uint64 LE ns).
"""

from __future__ import annotations

import json
import struct
import time
from dataclasses import dataclass, field
from typing import Any

from websockets.exceptions import InvalidStatus
from websockets.sync.client import ClientConnection, connect

#: The subprotocol foxglove-sdk 0.30.3 accepts (it answers 400 to foxglove.websocket.v1).
SUBPROTOCOL = 'foxglove.sdk.v1'
MESSAGE_DATA = 1
TIME = 2


@dataclass
class FoxgloveClient:
    """One connection: the server's info, its advertised channels, and what arrives."""

    connection: ClientConnection
    server_info: dict[str, Any] = field(default_factory=dict)
    channels: dict[str, dict[str, Any]] = field(default_factory=dict)
    _topic_of_subscription: dict[int, str] = field(default_factory=dict)

    def read_advertisements(self, topics: set[str], timeout_s: float = 60.0) -> None:
        """Read text frames until every topic of ``topics`` has been advertised."""
        deadline = time.monotonic() + timeout_s
        while not topics <= set(self.channels):
            frame = self.connection.recv(timeout=max(deadline - time.monotonic(), 0.01))
            if isinstance(frame, str):
                self._on_text(json.loads(frame))

    def _on_text(self, message: dict[str, Any]) -> None:
        if message['op'] == 'serverInfo':
            self.server_info = message
        elif message['op'] == 'advertise':
            for channel in message['channels']:
                self.channels[channel['topic']] = channel

    def subscribe(self, *topics: str) -> None:
        """Subscribe to advertised topics (subscription ids 1, 2, ...)."""
        subscriptions = []
        for topic in topics:
            subscription_id = len(self._topic_of_subscription) + 1
            self._topic_of_subscription[subscription_id] = topic
            subscriptions.append({'id': subscription_id,
                                  'channelId': self.channels[topic]['id']})
        self.connection.send(json.dumps({'op': 'subscribe', 'subscriptions': subscriptions}))

    def messages(self, counts: dict[str, int],
                 timeout_s: float = 120.0) -> dict[str, list[tuple[int, bytes]]]:
        """Receive until each topic has its count of messages: (log time ns, payload)."""
        received: dict[str, list[tuple[int, bytes]]] = {topic: [] for topic in counts}
        deadline = time.monotonic() + timeout_s
        while any(len(received[topic]) < n for topic, n in counts.items()):
            frame = self.connection.recv(timeout=max(deadline - time.monotonic(), 0.01))
            if isinstance(frame, str):
                self._on_text(json.loads(frame))
                continue
            if frame[0] != MESSAGE_DATA:
                continue
            subscription_id, log_time_ns = struct.unpack_from('<IQ', frame, 1)
            topic = self._topic_of_subscription[subscription_id]
            if topic in received:
                received[topic].append((log_time_ns, bytes(frame[13:])))
        return received

    def close(self) -> None:
        """Disconnect."""
        self.connection.close()


def connect_when_up(url: str, timeout_s: float = 120.0) -> FoxgloveClient:
    """Connect to a server that may still be starting (retries refused connections)."""
    deadline = time.monotonic() + timeout_s
    while True:
        connection: Any
        try:
            # No proxy from the environment: the live view is on loopback. legacy=True:
            # the connection outlives this call (closed by FoxgloveClient.close).
            connection = connect(url, subprotocols=[SUBPROTOCOL],  # type: ignore[list-item]
                                 open_timeout=10.0, max_size=None, proxy=None, legacy=True)
        except (ConnectionRefusedError, InvalidStatus, OSError):
            if time.monotonic() > deadline:
                raise
            time.sleep(0.2)
            continue
        assert connection.subprotocol == SUBPROTOCOL
        return FoxgloveClient(connection)
