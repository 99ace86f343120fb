"""When each UDP datagram reached the host: the kernel's time of it.

A bridge reads its socket once per period, so a message read at a poll may have arrived up to a
period earlier; with a periodic sender (ArduPilot's 50 Hz streams) and a periodic poll (60 Hz)
the two meet in a few fixed phases and the earliest read of a window can stay milliseconds
late. The kernel stamps each datagram as it arrives (Linux ``SO_TIMESTAMPNS``, the time in the
ancillary data of ``recvmsg``, on ``CLOCK_REALTIME``: the node clock's epoch when not
simulated)::

    arrival = DatagramArrival.attach(conn)     # None: not a UDP connection, or not Linux
    msg = conn.recv_match(blocking=False)
    arrival_s = arrival.last_s if arrival else None

A plain socket (the Net F/T link) asks with ``stamp_arrivals(sock)`` and reads the stamp from
``recvmsg``'s ancillary data with ``kernel_arrival_s(ancillary)``.

The connection's ``recv`` is replaced by one that does what pymavlink's ``mavudp.recv`` does
(the same datagram, the same bookkeeping of its peers) and keeps the kernel's time of it.
"""

from __future__ import annotations

import errno
import socket
import struct
import sys
import time
from typing import Any

#: Linux's SO_TIMESTAMPNS (``asm-generic/socket.h``: SO_TIMESTAMPNS_OLD, also its SCM type);
#: the Python socket module does not name it.
SO_TIMESTAMPNS = 35
#: Largest UDP datagram pymavlink reads (``mavutil.UDP_MAX_PACKET_LEN``).
UDP_MAX_PACKET_LEN = 65535
_TIMESPEC = struct.Struct('@qq')
#: Ancillary buffer ``recvmsg`` needs for the stamp.
ANCILLARY_SIZE = socket.CMSG_SPACE(_TIMESPEC.size)


def stamp_arrivals(sock: socket.socket) -> bool:
    """Ask the kernel to stamp each datagram's arrival; False where it cannot (not Linux)."""
    if not sys.platform.startswith('linux'):
        return False
    try:
        sock.setsockopt(socket.SOL_SOCKET, SO_TIMESTAMPNS, 1)
    except OSError:
        return False
    return True


def kernel_arrival_s(ancillary: list[tuple[int, int, bytes]]) -> float | None:
    """The kernel's arrival stamp in ``recvmsg``'s ancillary data (s since the epoch), or None."""
    for level, kind, payload in ancillary:
        if level == socket.SOL_SOCKET and kind == SO_TIMESTAMPNS and \
                len(payload) >= _TIMESPEC.size:
            seconds, nanoseconds = _TIMESPEC.unpack(payload[:_TIMESPEC.size])
            return seconds + nanoseconds * 1e-9
    return None


class DatagramArrival:
    """The kernel's arrival time of the datagram a pymavlink UDP connection read last."""

    def __init__(self, conn: Any) -> None:
        self.conn = conn
        #: Arrival of the last datagram read (s since the epoch), None before one.
        self.last_s: float | None = None

    @classmethod
    def attach(cls, conn: Any) -> DatagramArrival | None:
        """Stamp ``conn``'s datagrams on arrival; None where that cannot be done."""
        port = getattr(conn, 'port', None)
        if not isinstance(port, socket.socket) or port.type != socket.SOCK_DGRAM \
                or not hasattr(conn, 'udp_server') or not stamp_arrivals(port):
            return None
        arrival = cls(conn)
        conn.recv = arrival.recv
        return arrival

    def recv(self, n: int | None = None) -> bytes | str:
        """Read one datagram as ``mavudp.recv`` does, keeping its arrival in ``last_s``."""
        conn = self.conn
        try:
            data, ancillary, _, address = conn.port.recvmsg(UDP_MAX_PACKET_LEN, ANCILLARY_SIZE)
        except OSError as exc:
            if exc.errno in (errno.EAGAIN, errno.EWOULDBLOCK, errno.ECONNREFUSED):
                return ''
            raise
        arrival_s = kernel_arrival_s(ancillary)
        if arrival_s is not None:
            self.last_s = arrival_s
        if conn.udp_server:
            conn.clients.add(address)
            conn.clients_last_alive[address] = time.time()
        elif conn.broadcast:
            conn.last_address = address
        return bytes(data)
