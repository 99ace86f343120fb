"""When each UDP datagram of a pymavlink connection reached the host: the kernel's time of it.

A bridge reads its socket once per period, so a message read at a poll may have arrived up to a
period earlier; with a periodic sender (ArduPilot's 50 Hz streams) and a periodic poll (60 Hz)
the two meet in a few fixed phases and the earliest read of a window can stay milliseconds
late. The kernel stamps each datagram as it arrives (Linux ``SO_TIMESTAMPNS``, the time in the
ancillary data of ``recvmsg``, on ``CLOCK_REALTIME``: the node clock's epoch when not
simulated)::

    arrival = DatagramArrival.attach(conn)     # None: not a UDP connection, or not Linux
    msg = conn.recv_match(blocking=False)
    arrival_s = arrival.last_s if arrival else None

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
        if not sys.platform.startswith('linux') or not isinstance(port, socket.socket) \
                or port.type != socket.SOCK_DGRAM or not hasattr(conn, 'udp_server'):
            return None
        try:
            port.setsockopt(socket.SOL_SOCKET, SO_TIMESTAMPNS, 1)
        except OSError:
            return None
        arrival = cls(conn)
        conn.recv = arrival.recv
        return arrival

    def recv(self, n: int | None = None) -> bytes | str:
        """Read one datagram as ``mavudp.recv`` does, keeping its arrival in ``last_s``."""
        conn = self.conn
        try:
            data, ancillary, _, address = conn.port.recvmsg(
                UDP_MAX_PACKET_LEN, socket.CMSG_SPACE(_TIMESPEC.size))
        except OSError as exc:
            if exc.errno in (errno.EAGAIN, errno.EWOULDBLOCK, errno.ECONNREFUSED):
                return ''
            raise
        for level, kind, payload in ancillary:
            if level == socket.SOL_SOCKET and kind == SO_TIMESTAMPNS and \
                    len(payload) >= _TIMESPEC.size:
                seconds, nanoseconds = _TIMESPEC.unpack(payload[:_TIMESPEC.size])
                self.last_s = seconds + nanoseconds * 1e-9
        if conn.udp_server:
            conn.clients.add(address)
            conn.clients_last_alive[address] = time.time()
        elif conn.broadcast:
            conn.last_address = address
        return bytes(data)
