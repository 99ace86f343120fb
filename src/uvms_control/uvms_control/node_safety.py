"""What keeps the controller node alive and safe: survived faults, the allocator's state.

``guarded`` wraps a node callback so that no exception reaches the executor: the node's
``_fault(where, error)`` answers it (safe command, log, count). ``FaultLog`` counts those
faults, logs them throttled and gives /diagnostics the last one. ``AllocatorWatch`` follows
the thruster allocator's lifecycle state from what the allocator publishes: its
``<allocator>/transition_event`` (lifecycle_msgs/TransitionEvent), which every managed node
publishes at each transition, so the controller knows at once when the allocator stops
turning its commands into thrust.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any, TypeVar

from lifecycle_msgs.msg import State, TransitionEvent
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.qos import QoSProfile, ReliabilityPolicy

#: How long /diagnostics reports ERROR after a survived fault (s, steady clock).
FAULT_REPORT_S = 10.0
#: Throttle of the fault log line (s).
FAULT_LOG_PERIOD_S = 1.0

Callback = TypeVar('Callback', bound=Callable[..., Any])


def guarded(where: str) -> Callable[[Callback], Callback]:
    """Decorate a node method so that an exception becomes ``self._fault(where, error)``."""
    def wrap(callback: Callback) -> Callback:
        @functools.wraps(callback)
        def call(self: Any, *args: Any) -> Any:
            try:
                return callback(self, *args)
            except Exception as error:  # the executor must not die of it: answer safely
                return self._fault(where, error)
        return call  # type: ignore[return-value]
    return wrap


class FaultLog:
    """Exceptions a node survived: counted, logged (throttled), the last one kept.

    Args:
        logger: the node's logger.
    """

    def __init__(self, logger: Any) -> None:
        self._logger = logger
        self._steady = Clock(clock_type=ClockType.STEADY_TIME)
        self.count = 0
        self.last: str | None = None
        self._last_ns: int | None = None

    def record(self, where: str, error: BaseException, answer: str) -> str:
        """Count and log a fault in ``where``; ``answer`` says what the node did about it."""
        text = f'{where} failed: {type(error).__name__}: {error}'
        self.count += 1
        self.last = text
        self._last_ns = self._steady.now().nanoseconds
        self._logger.error(f'{text}; {answer} (faults so far: {self.count})',
                           throttle_duration_sec=FAULT_LOG_PERIOD_S)
        return text

    @property
    def recent(self) -> bool:
        """A fault in the last FAULT_REPORT_S seconds."""
        return (self._last_ns is not None
                and self._steady.now().nanoseconds - self._last_ns < FAULT_REPORT_S * 1e9)

    def values(self) -> dict[str, Any]:
        """Diagnostic key-values: the fault count and the last fault."""
        return {'faults': self.count, 'last_fault': self.last or 'none'}


class AllocatorWatch:
    """The thruster allocator's lifecycle state, from its ``transition_event`` topic.

    The allocator counts as active until it is seen leaving the active state (a transition
    that starts from active: deactivating, shutting down), and again once a transition ends
    in active. Its start-up transitions (configuring, activating) change nothing, so a graph
    whose nodes start in any order, or one without an allocator (another one, a test probe,
    hardware), runs as before. A killed allocator sends no event; the simulator's own
    command watchdog covers that case.

    Args:
        node: the controller node (relative names: the allocator in its namespace).
        allocator: the allocator's node name, e.g. 'thruster_allocator'.
        on_change: called with (active, state label) when its state changes.
    """

    def __init__(self, node: Node, allocator: str,
                 on_change: Callable[[bool, str], None]) -> None:
        self._on_change = on_change
        self.active = True
        self.label = 'unknown'
        self.subscription = node.create_subscription(
            TransitionEvent, f'{allocator}/transition_event', self._on_event,
            QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE))

    def _on_event(self, msg: TransitionEvent) -> None:
        self.label = msg.goal_state.label or str(msg.goal_state.id)
        if msg.goal_state.id == State.PRIMARY_STATE_ACTIVE:
            active = True
        elif msg.start_state.id == State.PRIMARY_STATE_ACTIVE:
            active = False
        else:
            return
        if active != self.active:
            self.active = active
            self._on_change(active, self.label)
