"""An ATI Net F/T box speaking RDT over UDP on 127.0.0.1, without ROS.

Follows shared/robots/bluerov2_heavy_alpha5.md, "ATI Net F/T (RDT over UDP)": a start request
(command 2) makes it stream 36-byte records to the requester at ``rate_hz``, for the requested
sample count (0: until stopped); command 0 stops. Other commands are ignored (their meaning is
in ATI's manual, not in the document). The plant sets the wrench in the sensor's own axes::

    with NetFtTwin(port=0, rate_hz=200.0) as twin:
        twin.set_wrench((1.0, 2.0, 3.0), (0.1, 0.2, 0.3))   # N, N m

Assumed (for docs/hardware.md): the status word is 0 unless the plant sets it; the twin's
ft_sequence equals its rdt_sequence; the rate is capped at `MAX_RATE_HZ` (the box's own
maximum is not in the document).
"""

from __future__ import annotations

import select
import socket
import threading
import time

from uvms_hardware import rdt_protocol as rdt
from uvms_hardware.address import LOOPBACK
from uvms_hardware.errors import ProtocolError

#: Largest record rate the twin streams at (Hz).
MAX_RATE_HZ = 1000.0


class NetFtTwin:
    """RDT server of one Net F/T box on UDP ``host:port`` (``port`` 0: ephemeral)."""

    def __init__(self, host: str = LOOPBACK, port: int = rdt.RDT_PORT, rate_hz: float = 1000.0,
                 counts_per_force: float = rdt.DEFAULT_COUNTS_PER_FORCE,
                 counts_per_torque: float = rdt.DEFAULT_COUNTS_PER_TORQUE) -> None:
        if not 0.0 < rate_hz:
            raise ValueError(f'rate_hz = {rate_hz!r}: expected > 0')
        self.period_s = 1.0 / min(rate_hz, MAX_RATE_HZ)
        self.counts_per_force = counts_per_force
        self.counts_per_torque = counts_per_torque
        self._address = (host, port)
        self.port = port
        self._lock = threading.Lock()
        self._counts: tuple[int, int, int, int, int, int] = (0, 0, 0, 0, 0, 0)
        self._status = 0
        self._sequence = 0
        self._skip = 0
        self._client: tuple[str, int] | None = None
        self._remaining = 0
        self._socket: socket.socket | None = None
        self._thread: threading.Thread | None = None
        self._running = threading.Event()
        #: Requests received that were no valid request.
        self.bad_requests = 0

    def set_wrench(self, force_xyz: tuple[float, float, float],
                   torque_xyz: tuple[float, float, float]) -> None:
        """The wrench the sensor feels, in its own axes (N, N m)."""
        counts = rdt.counts_from_wrench(force_xyz, torque_xyz, self.counts_per_force,
                                        self.counts_per_torque)
        with self._lock:
            self._counts = counts

    def set_status(self, status: int) -> None:
        """The status word of the next records."""
        with self._lock:
            self._status = status

    def drop_records(self, count: int) -> None:
        """Skip the next ``count`` sequence numbers (records lost on the way)."""
        with self._lock:
            self._skip += count

    @property
    def streaming(self) -> bool:
        """True while records are being sent."""
        with self._lock:
            return self._client is not None

    def handle(self, datagram: bytes, sender: tuple[str, int]) -> None:
        """Apply one request from ``sender``."""
        try:
            request = rdt.decode_request(datagram)
        except ProtocolError:
            self.bad_requests += 1
            return
        with self._lock:
            if request.command == rdt.COMMAND_START_REALTIME:
                self._client, self._remaining = sender, request.sample_count
            elif request.command == rdt.COMMAND_STOP:
                self._client = None

    def next_record(self) -> bytes:
        """The next record's datagram (advances the sequence)."""
        with self._lock:
            self._sequence = (self._sequence + 1 + self._skip) % (1 << 32)
            self._skip = 0
            return rdt.encode_record(rdt.Record(self._sequence, self._sequence, self._status,
                                                self._counts))

    def start(self) -> None:
        """Bind and serve in a background thread."""
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        sock.bind(self._address)
        self.port = sock.getsockname()[1]
        self._socket = sock
        self._running.set()
        self._thread = threading.Thread(target=self._serve, name='netft twin', daemon=True)
        self._thread.start()

    def stop(self) -> None:
        """Stop serving and close the socket (idempotent)."""
        self._running.clear()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
            self._thread = None
        if self._socket is not None:
            self._socket.close()
            self._socket = None

    def _serve(self) -> None:
        sock = self._socket
        assert sock is not None
        next_s = time.monotonic()
        while self._running.is_set():
            timeout = max(0.0, next_s - time.monotonic()) if self.streaming else 0.05
            readable, _, _ = select.select([sock], [], [], timeout)
            if readable:
                datagram, sender = sock.recvfrom(64)
                self.handle(datagram, sender)
                continue
            with self._lock:
                client = self._client
            if client is None:
                next_s = time.monotonic()
                continue
            sock.sendto(self.next_record(), client)
            next_s = max(next_s + self.period_s, time.monotonic() - self.period_s)
            with self._lock:
                if self._remaining > 0:
                    self._remaining -= 1
                    if self._remaining == 0:
                        self._client = None

    def __enter__(self) -> NetFtTwin:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()
