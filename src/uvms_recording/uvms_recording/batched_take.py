"""Taking a recorder's messages in batches, off the executor's per-message dispatch.

A recorder process receives a few thousand messages a second at the twin stand (the wrench,
odometry, commands and states at the control rate). Dispatched one by one by an executor,
each costs the recorder's thread several times the 5 us of writing it. Taken from each
subscription in a batch at 20 Hz, straight from the middleware's queue (``take_message``),
a stream of 3500 messages a second costs the recorder's process (its middleware threads
included) 10-11 % of a core against 17-18 % one EventsExecutor callback at a time: 0.58x
(bench/bench_recorder.py).

``TakenInBatches`` is the callback group that keeps the subscriptions out of an executor
that honours callback groups (rclpy's SingleThreadedExecutor and MultiThreadedExecutor:
neither waits on nor runs an entity whose group says it cannot execute). The EventsExecutor
does not ask the group and calls each message's callback: the node then records as before,
one message at a time, and its batch finds its queues empty.

A batch has no executor time to stamp its messages with, so each message's log time comes
from its arrival: the middleware's reception timestamp (rmw ``received_timestamp``, system
time in ns) on the wall clock, or, under ``use_sim_time``, the stamp of the last ``/clock``
message received before it (``log_times_on_clock``), which is what the node clock read when
the message arrived.
"""

from __future__ import annotations

import bisect
import time
from collections.abc import Sequence
from typing import Any

from rclpy.callback_groups import CallbackGroup


class TakenInBatches(CallbackGroup):
    """A callback group an executor never runs: its node takes the messages itself."""

    def can_execute(self, entity: Any) -> bool:
        """Never: the owner takes the entity's work in batches."""
        return False

    def beginning_execution(self, entity: Any) -> bool:
        """Refused, as ``can_execute`` says."""
        return False

    def ending_execution(self, entity: Any) -> None:
        """Nothing was begun."""


def take_raw(subscription: Any, limit: int) -> list[tuple[bytes, int]]:
    """Up to ``limit`` serialized messages waiting in a raw subscription, with their arrival.

    Returns:
        ``(cdr bytes, received ns)`` in arrival order; the reception time is the
        middleware's (system time), or ``time.time_ns()`` where the rmw gives none.

    """
    taken: list[tuple[bytes, int]] = []
    handle = subscription.handle
    msg_type = subscription.msg_type
    while len(taken) < limit:
        with handle:
            message = handle.take_message(msg_type, True)
        if message is None:
            break
        data, info = message
        taken.append((data, info.get('received_timestamp') or time.time_ns()))
    return taken


def log_times_on_clock(received_ns: Sequence[int], clock_received_ns: Sequence[int],
                       clock_stamps_ns: Sequence[int], before_ns: int) -> list[int]:
    """Simulated log times of messages: the last ``/clock`` stamp received before each.

    Args:
        received_ns: The messages' reception times (system time, ns).
        clock_received_ns: Reception times of the batch's ``/clock`` messages, ascending.
        clock_stamps_ns: Their stamps (simulated time, ns).
        before_ns: The clock's stamp before the batch's first ``/clock`` message.

    Example:
        Clocks stamped 10 and 20 received at 100 and 200: messages received at 50, 150 and
        250 are logged at ``before_ns``, 10 and 20.

    """
    times = []
    for received in received_ns:
        index = bisect.bisect_right(clock_received_ns, received)
        times.append(clock_stamps_ns[index - 1] if index else before_ns)
    return times
