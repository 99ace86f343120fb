"""A twin's UDP datagrams with the kernel's arrival time, on ``time.monotonic``.

The twin's line (``rs485_bus``) starts a frame when the host's adapter would have: when the
host wrote it, not when the twin's thread woke. On Linux the kernel stamps each datagram's
arrival (``SO_TIMESTAMPNS``, on CLOCK_REALTIME), converted here to the monotonic clock the
twin runs on; elsewhere the thread's reading is the arrival.
"""

from __future__ import annotations

import math
import socket
import time

from uvms_hardware.datagram_arrival import ANCILLARY_SIZE, kernel_arrival_s, stamp_arrivals

__all__ = ['receive_stamped', 'stamp_arrivals']


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
    datagram, ancillary, _, sender = sock.recvmsg(4096, ANCILLARY_SIZE)
    wall_s = kernel_arrival_s(ancillary)
    if wall_s is None:
        return datagram, sender, now_s
    return datagram, sender, min(now_s, wall_s - _wall_minus_steady_s())
