"""A twin's UDP datagrams with the kernel's arrival time, on ``time.monotonic``.

The twin's line (``rs485_bus``) starts a frame when the host's adapter would have: when the
host wrote it, not when the twin's thread woke. On Linux the kernel stamps each datagram's
arrival (``SO_TIMESTAMPNS``, on CLOCK_REALTIME), converted here to the monotonic clock the
twin runs on; elsewhere the thread's reading is the arrival.
"""

from __future__ import annotations

import math
import socket
import struct
import time

__all__ = ['receive_stamped', 'stamp_arrivals']

#: The kernel's arrival stamp of a datagram (Linux; None elsewhere: the thread's clock).
_SO_TIMESTAMPNS: int | None = getattr(socket, 'SO_TIMESTAMPNS', None)


def stamp_arrivals(sock: socket.socket) -> bool:
    """Ask the kernel to stamp each datagram's arrival (SO_TIMESTAMPNS); False: not here."""
    option = _SO_TIMESTAMPNS
    if option is None:
        return False
    try:
        sock.setsockopt(socket.SOL_SOCKET, option, 1)
    except OSError:
        return False
    return True


def _wall_minus_steady_s() -> float:
    """time.time() - time.monotonic() (s), from the tightest of a few bracketed readings.

    A thread preempted between its two clock reads would shift every stamp by the pause.
    """
    best = (math.inf, 0.0)
    for _ in range(3):
        before_s = time.monotonic()
        wall_s = time.time()
        after_s = time.monotonic()
        best = min(best, (after_s - before_s, wall_s - (before_s + after_s) / 2.0))
    return best[1]


def receive_stamped(sock: socket.socket, stamped: bool,
             now_s: float) -> tuple[bytes, tuple[str, int], float]:
    """(datagram, sender, arrival s on time.monotonic): the kernel's stamp when it gives one.

    The kernel's stamp is when the host wrote (loopback), however late this thread wakes: the
    line then starts the frame when the host's adapter would have.
    """
    if not stamped:
        datagram, sender = sock.recvfrom(4096)
        return datagram, sender, now_s
    datagram, ancillary, _, sender = sock.recvmsg(4096, 64)
    for level, kind, data in ancillary:
        if level == socket.SOL_SOCKET and kind == _SO_TIMESTAMPNS and len(data) >= 16:
            seconds, nanoseconds = struct.unpack('qq', data[:16])
            wall_s = seconds + nanoseconds * 1e-9
            return datagram, sender, min(now_s, wall_s - _wall_minus_steady_s())
    return datagram, sender, now_s
