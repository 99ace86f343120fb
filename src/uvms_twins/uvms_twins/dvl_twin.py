"""A Water Linked DVL A50/A125 twin: a TCP server streaming JSON reports. No ROS.

Follows Water Linked's "DVL protocol" documentation (TCP, port 16171, one JSON object per
line, newline-terminated): a velocity report (``"type": "velocity"``: time, vx, vy, vz, fom,
covariance, altitude, transducers, velocity_valid, status, format, time_of_validity,
time_of_transmission) at ``rate_hz`` to every connected client, and a dead-reckoning report
(``"type": "position_local"``) once a second. Velocities are in the DVL's frame (x forward,
y right, z down). A plant that measures (``report``: the simulator's DVL, one reading per
ping) has each reading sent at once, as the DVL reports each ping; the ``rate_hz`` stream then
only fills in while no reading comes (a DVL without lock still reports at its ping rate). The
figure of merit and covariance come from the plant: the twin does not model the acoustics.
Commands from the client are not answered (the bridge sends none). Binds 127.0.0.1, port 0 =
a free one.

Time, as the DVL's: ``clock`` is the DVL's own clock (s; Unix time by default, as a DVL
synchronised by NTP; the plant's time when a plant drives it). ``time_of_validity`` is the
centre of the ping: the plant's time of the reading when ``report`` is given one, else the
clock when the report is made; ``time_of_transmission`` is the clock just before the line is
sent (Water Linked's "DVL A50/A125 TCP JSON API", waterlinked/docs). Both in µs. ``sent_log``
keeps (time_of_validity s, time_of_transmission s, vx) of recent reports, for tests comparing
the bridge's stamps with what the twin sent.
"""

from __future__ import annotations

import argparse
import json
import socket
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any

from uvms_hardware.address import LOOPBACK


class DvlTwin:
    """The twin: a server thread; plant API ``set_velocity``; ``silent`` stops the stream."""

    def __init__(self, port: int = 0, host: str = LOOPBACK, rate_hz: float = 10.0,
                 clock: Callable[[], float] = time.time) -> None:
        self.rate_hz = rate_hz
        #: The DVL's own clock (s): what time_of_validity and time_of_transmission read.
        self.clock = clock
        #: (time_of_validity s, time_of_transmission s, vx m/s) of the last reports sent.
        self.sent_log: deque[tuple[float, float, float]] = deque(maxlen=10000)
        self._server = socket.create_server((host, port))
        self._server.settimeout(0.01)
        self.address: tuple[str, int] = self._server.getsockname()[:2]
        self._clients: list[socket.socket] = []
        self._lock = threading.Lock()
        self._send_lock = threading.Lock()  # one report at a time on a connection
        self._next_velocity_s = time.monotonic()
        self._last_report_s: float | None = None
        self._stop = threading.Event()
        self._velocity: dict[str, Any] = {'v': (0.0, 0.0, 0.0), 'valid': True, 'fom': 0.002,
                                          'altitude': 2.0}
        #: True: connections stay open but nothing is sent (a DVL gone silent).
        self.silent = False
        self.sent = 0
        self.connections = 0
        self._thread = threading.Thread(target=self._run, name='dvl twin', daemon=True)

    def start(self) -> DvlTwin:
        """Start serving; returns self."""
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop, close every connection and the server."""
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=2.0)
        self.drop_clients()
        self._server.close()

    def __enter__(self) -> DvlTwin:
        """Start."""
        return self.start()

    def __exit__(self, *exc: object) -> None:
        """Stop."""
        self.stop()

    @property
    def url(self) -> str:
        """``HOST:PORT`` for the bridge's ``address``."""
        return f'{self.address[0]}:{self.address[1]}'

    def set_velocity(self, v_body_m_s: tuple[float, float, float], valid: bool = True,
                     fom: float = 0.002, altitude_m: float = 2.0) -> None:
        """What the next reports say: velocity in the DVL frame (m/s), lock, fom, altitude."""
        with self._lock:
            self._velocity = {'v': tuple(v_body_m_s), 'valid': valid, 'fom': fom,
                              'altitude': altitude_m}

    def report(self, v_body_m_s: tuple[float, float, float], valid: bool = True,
               fom: float = 0.002, altitude_m: float = 2.0,
               time_of_validity_s: float | None = None) -> None:
        """A new reading (one ping): sent now, and the ``rate_hz`` stream waits a period.

        ``time_of_validity_s``: when the plant measured it, on the twin's ``clock`` (s); now
        when not given.
        """
        self.set_velocity(v_body_m_s, valid, fom, altitude_m)
        if not self.silent:
            self._send_velocity(time.monotonic(), time_of_validity_s)

    def send_raw(self, data: bytes) -> None:
        """Bytes to every client as they are (malformed lines for the tests)."""
        with self._lock:
            clients = list(self._clients)
        for client in clients:
            self._send(client, data)

    def drop_clients(self) -> None:
        """Close every connection (a DVL rebooting)."""
        with self._lock:
            clients, self._clients = self._clients, []
        for client in clients:
            client.close()

    def client_count(self) -> int:
        """Connections open now."""
        with self._lock:
            return len(self._clients)

    def velocity_line(self, time_of_validity_s: float,
                      time_of_transmission_s: float | None = None) -> bytes:
        """One velocity report as Water Linked's documentation shows it (json_v3.1).

        Times on the twin's clock (s); the transmission time is the validity time when not
        given.
        """
        sent_s = time_of_validity_s if time_of_transmission_s is None else time_of_transmission_s
        with self._lock:
            p = dict(self._velocity)
            since_s = (1.0 / self.rate_hz if self._last_report_s is None
                       else time.monotonic() - self._last_report_s)
        fom = float(p['fom'])
        vx, vy, vz = p['v']
        report = {
            'time': 1000.0 * since_s, 'vx': vx, 'vy': vy, 'vz': vz, 'fom': fom,
            'covariance': [[fom * fom if i == j else 0.0 for j in range(3)] for i in range(3)],
            'altitude': p['altitude'] if p['valid'] else -1.0,
            'transducers': [{'id': i, 'velocity': 0.0, 'distance': p['altitude'], 'rssi': -30.0,
                             'nsd': -90.0, 'beam_valid': p['valid']} for i in range(4)],
            'velocity_valid': p['valid'], 'status': 0, 'format': 'json_v3.1',
            'type': 'velocity', 'time_of_validity': round(time_of_validity_s * 1e6),
            'time_of_transmission': round(sent_s * 1e6)}
        return (json.dumps(report) + '\n').encode()

    @staticmethod
    def position_line(now_s: float) -> bytes:
        """A dead-reckoning report (the bridge ignores these)."""
        report = {'ts': now_s, 'x': 0.0, 'y': 0.0, 'z': 0.0, 'std': 0.0, 'roll': 0.0,
                  'pitch': 0.0, 'yaw': 0.0, 'type': 'position_local', 'status': 0,
                  'format': 'json_v3.1'}
        return (json.dumps(report) + '\n').encode()

    def _send_velocity(self, monotonic_s: float, time_of_validity_s: float | None = None
                       ) -> None:
        sent_s = self.clock()
        validity_s = sent_s if time_of_validity_s is None else time_of_validity_s
        line = self.velocity_line(validity_s, sent_s)
        with self._lock:
            self._next_velocity_s = monotonic_s + 1.0 / self.rate_hz
            self._last_report_s = monotonic_s
            self.sent += 1
            self.sent_log.append((validity_s, sent_s, float(self._velocity['v'][0])))
        self.send_raw(line)

    def _send(self, client: socket.socket, data: bytes) -> None:
        try:
            with self._send_lock:
                client.sendall(data)
        except OSError:
            with self._lock:
                if client in self._clients:
                    self._clients.remove(client)
            client.close()

    def _run(self) -> None:
        next_position_s = time.monotonic()
        while not self._stop.is_set():
            try:
                client, _ = self._server.accept()
                with self._lock:
                    self._clients.append(client)
                    self.connections += 1
            except (TimeoutError, OSError):
                pass
            now_s = time.monotonic()
            if self.silent:
                with self._lock:
                    self._next_velocity_s = next_position_s = now_s
                continue
            with self._lock:
                due = now_s >= self._next_velocity_s
            if due:
                self._send_velocity(now_s)
            if now_s >= next_position_s:
                next_position_s += 1.0
                self.send_raw(self.position_line(self.clock()))


def main(argv: list[str] | None = None) -> None:
    """Run the twin on 127.0.0.1 until interrupted: ``python -m ...dvl_twin --port N``."""
    parser = argparse.ArgumentParser(description='A Water Linked DVL twin (TCP JSON).')
    parser.add_argument('--port', type=int, default=16171)
    parser.add_argument('--rate-hz', type=float, default=10.0)
    args = parser.parse_args(argv)
    with DvlTwin(port=args.port, rate_hz=args.rate_hz) as twin:
        print(f'dvl twin on {twin.url}', flush=True)
        try:
            while True:
                time.sleep(1.0)
        except KeyboardInterrupt:
            pass


if __name__ == '__main__':
    main()
