"""An ATI Net F/T box speaking RDT over UDP on 127.0.0.1, without ROS.

Follows shared/robots/bluerov2_heavy_alpha5.md, "ATI Net F/T (RDT over UDP)": a start request
(command 2) makes it stream 36-byte records to the requester at ``rate_hz``, for the requested
sample count (0: until stopped); command 0 stops. Other commands are ignored (their meaning is
in ATI's manual, not in the document). The plant sets the wrench in the sensor's own axes::

    with NetFtTwin(port=0, rate_hz=200.0) as twin:
        twin.set_wrench((1.0, 2.0, 3.0), (0.1, 0.2, 0.3))   # N, N m

Time, as the box's: record k of a stream (its rdt_sequence, from 1 at each start request) is
the sample taken at ``t0 + k / rate_hz`` on the twin's ``clock`` (t0: the start request), so
the sequence is the box's clock at its configured rate whatever the host does to the twin's
thread: a twin woken late sends every sample due at once (up to `MAX_BURST`; older ones are
lost, their sequence numbers skipped), never a record with a late sample time.
``sample_time_s(sequence)`` says when a record was sampled, for tests comparing the bridge's
stamps with it.

Calibration, as the box serves it: with ``http_port`` (0: a free one) the twin answers
``GET /netftapi2.xml`` (any ``?index=``) on ``host`` with its one configuration (``setcfgsel``
0), its counts per force and torque (``cfgcpf``, ``cfgcpt``, per ``scfgfu`` N and ``scfgtu``
N-m) and its RDT rate (``comrdtrate``), the fields ATI's Net F/T demo code reads (see
`uvms_hardware.rdt_protocol`).

Assumed (for docs/hardware.md): the status word is 0 unless the plant sets it; rdt_sequence
restarts at 1 with each start request and ft_sequence counts the twin's samples since it
started (ATI's manual is not in the document); the rate is capped at `MAX_RATE_HZ` (the box's
own maximum is not in the document).
"""

from __future__ import annotations

import math
import select
import socket
import threading
import time
from collections.abc import Callable
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

from uvms_hardware.address import LOOPBACK
from uvms_hardware.errors import ProtocolError

from uvms_hardware import latency_probe
from uvms_hardware import rdt_protocol as rdt

#: Largest record rate the twin streams at (Hz).
MAX_RATE_HZ = 1000.0
#: Most records a late twin sends at once; older samples are lost (their sequences skipped).
MAX_BURST = 1000


class NetFtTwin:
    """RDT server of one Net F/T box on UDP ``host:port`` (``port`` 0: ephemeral)."""

    def __init__(self, host: str = LOOPBACK, port: int = rdt.RDT_PORT, rate_hz: float = 1000.0,
                 counts_per_force: float = rdt.DEFAULT_COUNTS_PER_FORCE,
                 counts_per_torque: float = rdt.DEFAULT_COUNTS_PER_TORQUE,
                 clock: Callable[[], float] = time.monotonic,
                 http_port: int | None = None) -> None:
        if not 0.0 < rate_hz:
            raise ValueError(f'rate_hz = {rate_hz!r}: expected > 0')
        self.period_s = 1.0 / min(rate_hz, MAX_RATE_HZ)
        self.counts_per_force = counts_per_force
        self.counts_per_torque = counts_per_torque
        #: The box's clock (s): its samples are taken on it.
        self.clock = clock
        self._address = (host, port)
        self.port = port
        self._http_address = None if http_port is None else (host, http_port)
        #: Port of the calibration page (``http_port`` given), else None.
        self.http_port: int | None = None
        self._http: ThreadingHTTPServer | None = None
        self._lock = threading.Lock()
        self._counts: tuple[int, int, int, int, int, int] = (0, 0, 0, 0, 0, 0)
        self._status = 0
        self._skip = 0
        self._client: tuple[str, int] | None = None
        self._remaining = 0
        self._stream_start_s = 0.0
        self._sample = 0  # the last sample of this stream sent or lost
        self._twin_start_s = clock()
        self._socket: socket.socket | None = None
        self._thread: threading.Thread | None = None
        self._running = threading.Event()
        #: Requests received that were no valid request.
        self.bad_requests = 0
        #: Samples a late twin could not send (their sequences skipped).
        self.burst_lost = 0

    @property
    def rate_hz(self) -> float:
        """Records per second of the stream (Hz)."""
        return 1.0 / self.period_s

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
        """The next ``count`` samples are lost on the way (their sequence numbers skipped)."""
        with self._lock:
            self._skip += count

    @property
    def streaming(self) -> bool:
        """True while records are being sent."""
        with self._lock:
            return self._client is not None

    def sample_time_s(self, sequence: int) -> float:
        """When record ``sequence`` of the present stream was sampled, on ``clock`` (s)."""
        with self._lock:
            return self._stream_start_s + sequence * self.period_s

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
                self._stream_start_s, self._sample = self.clock(), 0
            elif request.command == rdt.COMMAND_STOP:
                self._client = None

    def next_record(self) -> bytes:
        """The next sample's datagram (advances the sequence; a skipped one is lost)."""
        with self._lock:
            self._sample += 1 + self._skip
            self._skip = 0
            return self._record()

    def netftapi2_xml(self) -> str:
        """The calibration page as the box serves it (the fields ATI's demo code reads)."""
        return ('<?xml version="1.0" encoding="utf-8"?>\n<netft><setcfgsel>0</setcfgsel>'
                f'<cfgcpf>{round(self.counts_per_force)}</cfgcpf>'
                f'<cfgcpt>{round(self.counts_per_torque)}</cfgcpt>'
                '<scfgfu>N</scfgfu><scfgtu>N-m</scfgtu>'
                f'<comrdtrate>{round(self.rate_hz)}</comrdtrate></netft>\n')

    def start(self) -> None:
        """Bind and serve in background threads."""
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        sock.bind(self._address)
        self.port = sock.getsockname()[1]
        self._socket = sock
        if self._http_address is not None:
            self._http = ThreadingHTTPServer(self._http_address, _page_handler(self))
            self.http_port = self._http.server_address[1]
            threading.Thread(target=self._http.serve_forever, name='netft twin http',
                             daemon=True).start()
        self._running.set()
        self._thread = threading.Thread(target=self._serve, name='netft twin', daemon=True)
        self._thread.start()

    def stop(self) -> None:
        """Stop serving and close the sockets (idempotent)."""
        self._running.clear()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
            self._thread = None
        if self._socket is not None:
            self._socket.close()
            self._socket = None
        if self._http is not None:
            self._http.shutdown()
            self._http.server_close()
            self._http = None

    def _record(self) -> bytes:
        sequence = self._sample % (1 << 32)
        sample_s = self._stream_start_s + self._sample * self.period_s
        ft_sequence = round((sample_s - self._twin_start_s) / self.period_s) % (1 << 32)
        return rdt.encode_record(rdt.Record(sequence, ft_sequence, self._status, self._counts))

    def _due(self) -> tuple[list[bytes], float]:
        """Records of the samples due now, and seconds until the next one."""
        records: list[bytes] = []
        with self._lock:
            if self._client is None:
                return records, 0.05
            due = math.floor((self.clock() - self._stream_start_s) / self.period_s)
            if due - self._sample > MAX_BURST:
                self.burst_lost += due - MAX_BURST - self._sample
                self._sample = due - MAX_BURST
            while self._sample < due and self._client is not None:
                self._sample += 1
                if self._skip:
                    self._skip -= 1
                    continue
                records.append(self._record())
                if self._remaining > 0:
                    self._remaining -= 1
                    if self._remaining == 0:
                        self._client = None
            wait_s = self._stream_start_s + (self._sample + 1) * self.period_s - self.clock()
        return records, max(0.0, wait_s)

    def _serve(self) -> None:
        sock = self._socket
        assert sock is not None
        port = sock.getsockname()[1]
        while self._running.is_set():
            with self._lock:
                client = self._client
            records, wait_s = self._due()
            for record in records:
                if client is not None:
                    sock.sendto(record, client)
                    latency_probe.note('reply', port, int.from_bytes(record[:4], 'big'))
            readable, _, _ = select.select([sock], [], [], min(wait_s, 0.05))
            if readable:
                datagram, sender = sock.recvfrom(64)
                self.handle(datagram, sender)

    def __enter__(self) -> NetFtTwin:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()


def _page_handler(twin: NetFtTwin) -> type[BaseHTTPRequestHandler]:
    class Page(BaseHTTPRequestHandler):
        def do_GET(self) -> None:
            if self.path.split('?')[0] != '/netftapi2.xml':
                self.send_error(404)
                return
            body = twin.netftapi2_xml().encode()
            self.send_response(200)
            self.send_header('Content-Type', 'text/xml')
            self.send_header('Content-Length', str(len(body)))
            self.end_headers()
            self.wfile.write(body)

        def log_message(self, format: str, *args: object) -> None:
            pass

    return Page
