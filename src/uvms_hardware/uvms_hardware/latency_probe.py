"""Times of device datagrams and commands, for the device-to-command latency bench.

With ``UVMS_LATENCY_PROBE`` naming a directory, the twins note when each reply or record
leaves them and the bridges when they read datagrams and when a command leaves them, on
``CLOCK_MONOTONIC`` (one clock for every process of the machine), each process into
``<directory>/probe-<pid>.txt``: one line ``kind t_ns value`` per event. Unset (the default),
`note` returns at once and nothing is written. ``bench/bench_twin_latency.py`` pairs them:
reply i of a device is the i-th datagram its bridge read (loopback UDP neither loses nor
reorders), and the command it causes is the first one that leaves after that read.

Kinds: ``reply <port> [<sequence>]`` (a twin sent a datagram from ``port``; a Net F/T
record's RDT sequence), ``rx <port> <n>`` (a bridge read ``n`` datagrams from ``port``),
``ftrx 0 <sequence>`` (the Net F/T bridge read that record), ``current`` (the Alpha 5's
CURRENT frames left the bridge), ``rc`` (the ArduSub's RC overrides left the bridge). The
Net F/T's records are paired by their sequence: its bridge drops records read before it is
active, so counting would not pair them.
"""

from __future__ import annotations

import atexit
import os
import threading
import time

__all__ = ['ENV', 'enabled', 'flush', 'note']

#: The environment variable naming the directory of the notes.
ENV = 'UVMS_LATENCY_PROBE'
#: Notes kept before a write to the file.
BATCH = 512

_DIRECTORY = os.environ.get(ENV, '')
_LINES: list[str] = []
_LOCK = threading.Lock()


def enabled() -> bool:
    """Whether notes are taken (``UVMS_LATENCY_PROBE`` set)."""
    return bool(_DIRECTORY)


def note(kind: str, value: int = 0, extra: int = 0) -> None:
    """One event now (nothing without ``UVMS_LATENCY_PROBE``)."""
    if not _DIRECTORY:
        return
    line = f'{kind} {time.monotonic_ns()} {value} {extra}\n'
    with _LOCK:
        _LINES.append(line)
        full = len(_LINES) >= BATCH
    if full:
        flush()


def flush() -> None:
    """Append the notes taken to this process's file."""
    if not _DIRECTORY:
        return
    with _LOCK:
        lines = list(_LINES)
        _LINES.clear()
    if lines:
        os.makedirs(_DIRECTORY, exist_ok=True)
        with open(os.path.join(_DIRECTORY, f'probe-{os.getpid()}.txt'), 'a') as out:
            out.writelines(lines)


atexit.register(flush)
