"""Clocks: system, steady and ROS time (overridable by /clock), with time-jump callbacks."""

from __future__ import annotations

import threading
import time as _time
from collections.abc import Callable
from enum import IntEnum
from typing import TYPE_CHECKING

from rclpy.clock_type import ClockType
from rclpy.duration import Duration
from rclpy.time import Time

if TYPE_CHECKING:
    from rclpy.context import Context

__all__ = ['Clock', 'ClockChange', 'ClockType', 'JumpHandle', 'JumpThreshold', 'ROSClock',
           'TimeJump']


class ClockChange(IntEnum):
    """Kind of clock change reported with a time jump (``rcl_clock_change_t``)."""

    ROS_TIME_NO_CHANGE = 1
    ROS_TIME_ACTIVATED = 2
    ROS_TIME_DEACTIVATED = 3
    SYSTEM_TIME_NO_CHANGE = 4


class JumpThreshold:
    """Which time jumps a jump callback wants to hear about.

    Args:
        min_forward: Smallest forward jump reported (positive), or None for none.
        min_backward: Smallest backward jump reported (negative), or None for none.
        on_clock_change: Whether a switch to or from ROS time is reported.

    Raises:
        ValueError: If ``min_forward`` is not positive or ``min_backward`` not negative.
    """

    def __init__(
        self,
        *,
        min_forward: Duration | None,
        min_backward: Duration | None,
        on_clock_change: bool = True,
    ) -> None:
        if min_forward is not None and min_forward.nanoseconds <= 0:
            raise ValueError('min_forward must be a positive non-zero duration')
        if min_backward is not None and min_backward.nanoseconds >= 0:
            raise ValueError('min_backward must be a negative non-zero duration')
        if min_forward is None and min_backward is None and not on_clock_change:
            raise ValueError('At least one jump threshold must be enabled')
        self.min_forward = min_forward
        self.min_backward = min_backward
        self.on_clock_change = on_clock_change

    def _matches(self, clock_change: ClockChange, delta_ns: int) -> bool:
        if clock_change in (ClockChange.ROS_TIME_ACTIVATED, ClockChange.ROS_TIME_DEACTIVATED):
            return self.on_clock_change
        if self.min_forward is not None and delta_ns >= self.min_forward.nanoseconds:
            return True
        return self.min_backward is not None and delta_ns <= self.min_backward.nanoseconds


class TimeJump:
    """A change of the time a clock reports: the kind of change and the jump."""

    def __init__(self, clock_change: ClockChange, delta: Duration) -> None:
        self._clock_change = clock_change
        self._delta = delta

    @property
    def clock_change(self) -> ClockChange:
        """Kind of change (ROS time activated, deactivated, or none)."""
        return self._clock_change

    @property
    def delta(self) -> Duration:
        """Size of the jump (new time minus old time)."""
        return self._delta


class JumpHandle:
    """Registration of a jump callback on a clock; ``unregister`` removes it."""

    def __init__(
        self,
        clock: Clock,
        threshold: JumpThreshold,
        pre_callback: Callable[[], None] | None,
        post_callback: Callable[[TimeJump], None] | None,
    ) -> None:
        self._clock: Clock | None = clock
        self._threshold = threshold
        self._pre_callback = pre_callback
        self._post_callback = post_callback

    def unregister(self) -> None:
        """Stop receiving jump notifications."""
        if self._clock is not None:
            self._clock._remove_jump_handle(self)
            self._clock = None

    def __enter__(self) -> JumpHandle:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.unregister()


_NOW_NS = {
    ClockType.SYSTEM_TIME: _time.time_ns,
    ClockType.STEADY_TIME: _time.monotonic_ns,
}


class Clock:
    """A source of time points.

    ``Clock(clock_type=ClockType.ROS_TIME)`` returns a :class:`ROSClock`, as in rclpy.

    Args:
        clock_type: SYSTEM_TIME (wall clock), STEADY_TIME (monotonic) or ROS_TIME.
    """

    def __new__(cls, *, clock_type: ClockType = ClockType.SYSTEM_TIME) -> Clock:
        """Create a Clock, or a ROSClock for ROS_TIME."""
        if not isinstance(clock_type, ClockType):
            raise TypeError('Clock type must be a ClockType enum')
        if clock_type is ClockType.ROS_TIME and cls is Clock:
            cls = ROSClock
        return super().__new__(cls)

    def __init__(self, *, clock_type: ClockType = ClockType.SYSTEM_TIME) -> None:
        if clock_type is ClockType.UNINITIALIZED:
            raise ValueError('Clock type must be initialized (not UNINITIALIZED)')
        self._clock_type = clock_type
        self._jump_handles: list[JumpHandle] = []
        self._lock = threading.RLock()
        self._now_ns_impl = _NOW_NS.get(clock_type, _time.time_ns)

    @property
    def clock_type(self) -> ClockType:
        """Time source of this clock."""
        return self._clock_type

    def __repr__(self) -> str:
        return f'Clock(clock_type={self._clock_type.name})'

    def _now_ns(self) -> int:
        return self._now_ns_impl()

    def now(self) -> Time:
        """Return the current time of this clock."""
        return Time._from_ns(self._now_ns(), self._clock_type)

    def create_jump_callback(
        self,
        threshold: JumpThreshold,
        *,
        pre_callback: Callable[[], None] | None = None,
        post_callback: Callable[[TimeJump], None] | None = None,
    ) -> JumpHandle:
        """Register callbacks called before and after the time of this clock jumps.

        Args:
            threshold: Which jumps to report.
            pre_callback: Called with no argument before the jump.
            post_callback: Called with a :class:`TimeJump` after the jump.

        Returns:
            A handle whose ``unregister()`` removes the callbacks.
        """
        if pre_callback is not None and not callable(pre_callback):
            raise ValueError('pre_callback must be callable if given')
        if post_callback is not None and not callable(post_callback):
            raise ValueError('post_callback must be callable if given')
        handle = JumpHandle(self, threshold, pre_callback, post_callback)
        with self._lock:
            self._jump_handles.append(handle)
        return handle

    def _remove_jump_handle(self, handle: JumpHandle) -> None:
        with self._lock:
            if handle in self._jump_handles:
                self._jump_handles.remove(handle)

    def _call_jump_callbacks(self, clock_change: ClockChange, delta_ns: int, before: bool) -> None:
        with self._lock:
            handles = list(self._jump_handles)
        jump = TimeJump(clock_change, Duration(nanoseconds=delta_ns))
        for handle in handles:
            if not handle._threshold._matches(clock_change, delta_ns):
                continue
            if before and handle._pre_callback is not None:
                handle._pre_callback()
            elif not before and handle._post_callback is not None:
                handle._post_callback(jump)

    def sleep_until(self, until: Time, context: Context | None = None) -> bool:
        """Sleep until this clock reaches ``until``.

        Args:
            until: Time point of this clock's type to wake at.
            context: Context whose shutdown interrupts the sleep (default context if None).

        Returns:
            True once the time is reached; False if the context was shut down first.

        Raises:
            TypeError: If ``until`` is not a Time or has another clock type.
        """
        from rclpy.utilities import get_default_context

        if not isinstance(until, Time):
            raise TypeError('until must be a Time instance')
        if until.clock_type != self._clock_type:
            raise TypeError("until's clock type does not match this clock's type")
        context = get_default_context() if context is None else context
        if not context.ok():
            return False
        event = threading.Event()
        context.on_shutdown(event.set)
        handle = self.create_jump_callback(
            JumpThreshold(
                min_forward=Duration(nanoseconds=1),
                min_backward=Duration(nanoseconds=-1),
                on_clock_change=True,
            ),
            post_callback=lambda _jump: event.set(),
        )
        try:
            while context.ok():
                remaining_ns = until.nanoseconds - self._now_ns()
                if remaining_ns <= 0:
                    return True
                event.clear()
                if self._sleeps_on_wall_time():
                    event.wait(remaining_ns / 1e9)
                else:
                    event.wait(0.1)
            return False
        finally:
            handle.unregister()

    def sleep_for(self, rel_time: Duration, context: Context | None = None) -> bool:
        """Sleep for ``rel_time`` of this clock; see :meth:`sleep_until`."""
        return self.sleep_until(self.now() + rel_time, context)

    def _sleeps_on_wall_time(self) -> bool:
        return True


class ROSClock(Clock):
    """Clock of ROS time: system time, or the time set by /clock while ROS time is active."""

    def __new__(cls) -> ROSClock:
        """Create a ROS clock."""
        return super().__new__(cls, clock_type=ClockType.ROS_TIME)  # type: ignore[return-value]

    def __init__(self, *, clock_type: ClockType = ClockType.ROS_TIME) -> None:
        super().__init__(clock_type=ClockType.ROS_TIME)
        self._ros_time_is_active = False
        self._override_ns = 0

    def _now_ns(self) -> int:
        if self._ros_time_is_active:
            return self._override_ns
        return _time.time_ns()

    @property
    def ros_time_is_active(self) -> bool:
        """Whether the clock follows the overridden (simulated) time."""
        return self._ros_time_is_active

    def _set_ros_time_is_active(self, enabled: bool) -> None:
        if enabled == self._ros_time_is_active:
            return
        change = ClockChange.ROS_TIME_ACTIVATED if enabled else ClockChange.ROS_TIME_DEACTIVATED
        self._call_jump_callbacks(change, 0, before=True)
        with self._lock:
            self._ros_time_is_active = enabled
        self._call_jump_callbacks(change, 0, before=False)

    def set_ros_time_override(self, time: Time) -> None:
        """Set the time the clock reports while ROS time is active.

        Raises:
            TypeError: If ``time`` is not a Time.
        """
        if not isinstance(time, Time):
            raise TypeError('Time must be specified as rclpy.time.Time')
        # Without jump handles (no timer on this clock) there is nobody to tell: skip the
        # TimeJump objects; this runs once per /clock message per node.
        notify = self._ros_time_is_active and bool(self._jump_handles)
        delta_ns = time.nanoseconds - self._override_ns
        if notify:
            self._call_jump_callbacks(ClockChange.ROS_TIME_NO_CHANGE, delta_ns, before=True)
        with self._lock:
            self._override_ns = time.nanoseconds
        if notify:
            self._call_jump_callbacks(ClockChange.ROS_TIME_NO_CHANGE, delta_ns, before=False)

    def _sleeps_on_wall_time(self) -> bool:
        return not self._ros_time_is_active
