"""Timers on a clock, with rcl's timing rules (missed periods skipped, sim-time jumps)."""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from rclpy.clock import Clock, ClockChange, JumpThreshold, ROSClock, TimeJump
from rclpy.duration import Duration
from rclpy.exceptions import InvalidHandle, ROSInterruptException

if TYPE_CHECKING:
    from rclpy.callback_groups import CallbackGroup
    from rclpy.context import Context


class Timer:
    """Calls ``callback`` every ``timer_period_ns`` of ``clock`` when spun by an executor.

    As rcl: the next call time advances by exactly one period per call; periods missed while
    the callback could not run are skipped; on a ROS clock driven by /clock the timer fires when
    the simulated time reaches its next call time, and a backwards jump restarts the period.

    Args:
        callback: Called with no argument (None for a timer that only wakes, as Rate uses).
        callback_group: Group the callback belongs to.
        timer_period_ns: Period in nanoseconds (non-negative).
        clock: Clock the timer reads.
        context: Context of the timer (the default context if None).
        autostart: Start now; otherwise the timer starts canceled until ``reset()``.

    Raises:
        ValueError: If the period is negative.
    """

    def __init__(
        self,
        callback: Callable[[], Any] | None,
        callback_group: CallbackGroup | None,
        timer_period_ns: int,
        clock: Clock,
        *,
        context: Context | None = None,
        autostart: bool = True,
    ) -> None:
        from rclpy.utilities import get_default_context

        if timer_period_ns < 0:
            raise ValueError(
                f'timer period must be non-negative, got {timer_period_ns} ns'
            )
        self._context = get_default_context() if context is None else context
        self.callback = callback
        self.callback_group = callback_group
        self._clock = clock
        self._period = int(timer_period_ns)
        self._lock = threading.Lock()
        now = clock._now_ns()
        self._last_call = now
        self._next_call = now + self._period
        self._time_credit = 0
        self._canceled = not autostart
        self._executor_event = False
        self._node: Any = None
        self._destroyed = False
        self._jump_handle = None
        if isinstance(clock, ROSClock):
            self._jump_handle = clock.create_jump_callback(
                JumpThreshold(
                    min_forward=Duration(nanoseconds=1),
                    min_backward=Duration(nanoseconds=-1),
                    on_clock_change=True,
                ),
                pre_callback=self._before_jump,
                post_callback=self._after_jump,
            )

    @property
    def handle(self) -> Timer:
        """Handle of the timer (usable in ``with``)."""
        self._check()
        return self

    def __enter__(self) -> Timer:
        return self

    def __exit__(self, *exc_info: object) -> None:
        return None

    def _check(self) -> None:
        if self._destroyed:
            raise InvalidHandle('cannot use Destroyable because destruction was requested')

    @property
    def clock(self) -> Clock:
        """Clock the timer reads."""
        return self._clock

    @property
    def timer_period_ns(self) -> int:
        """Period in nanoseconds (settable; the next call time is not moved)."""
        return self._period

    @timer_period_ns.setter
    def timer_period_ns(self, value: int) -> None:
        if value < 0:
            raise ValueError(f'timer period must be non-negative, got {value} ns')
        self._period = int(value)

    def _ready(self) -> bool:
        return not self._canceled and self._clock._now_ns() >= self._next_call

    def _wait_ns(self) -> int | None:
        """Nanoseconds of wall time until ready, or None if only a clock jump can make it so."""
        clock = self._clock
        if isinstance(clock, ROSClock) and clock._ros_time_is_active:
            return None
        return self._next_call - clock._now_ns()

    def is_ready(self) -> bool:
        """Tell whether the timer is due (and not canceled)."""
        self._check()
        return self._ready()

    def is_canceled(self) -> bool:
        """Tell whether the timer is canceled."""
        self._check()
        return self._canceled

    def cancel(self) -> None:
        """Stop the timer until ``reset()``."""
        self._check()
        self._canceled = True

    def reset(self) -> None:
        """Restart the period from now (and un-cancel)."""
        self._check()
        with self._lock:
            self._next_call = self._clock._now_ns() + self._period
            self._canceled = False
        self._wake()

    def time_since_last_call(self) -> int:
        """Nanoseconds of the timer's clock since the last call (or creation)."""
        self._check()
        return self._clock._now_ns() - self._last_call

    def time_until_next_call(self) -> int | None:
        """Nanoseconds of the timer's clock until the next call; None if canceled."""
        self._check()
        if self._canceled:
            return None
        return self._next_call - self._clock._now_ns()

    def _call(self) -> bool:
        """Advance the timer as ``rcl_timer_call`` does; False if it is canceled."""
        if self._canceled:
            return False
        with self._lock:
            now = self._clock._now_ns()
            self._last_call = now
            next_call = self._next_call + self._period
            if next_call < now:
                if self._period == 0:
                    next_call = now
                else:
                    periods_ahead = 1 + (now - next_call - 1) // self._period
                    next_call += periods_ahead * self._period
            self._next_call = next_call
        return True

    def _before_jump(self) -> None:
        now = self._clock._now_ns()
        if now != 0:
            self._time_credit = self._next_call - now

    def _after_jump(self, jump: TimeJump) -> None:
        now = self._clock._now_ns()
        with self._lock:
            if jump.clock_change in (ClockChange.ROS_TIME_ACTIVATED,
                                     ClockChange.ROS_TIME_DEACTIVATED):
                if now == 0:
                    return
                credit, self._time_credit = self._time_credit, 0
                if credit:
                    self._next_call = now - credit + self._period
                    self._last_call = now - credit
            elif now < self._last_call and self._next_call > now:
                self._next_call = now + self._period
                self._last_call = now
        self._wake()

    def _wake(self) -> None:
        node = self._node
        executor = node._executor if node is not None else None
        if executor is not None:
            executor._wake()

    def destroy(self) -> None:
        """Destroy the timer: it never fires again."""
        self._canceled = True
        self._destroyed = True
        if self._jump_handle is not None:
            self._jump_handle.unregister()
            self._jump_handle = None


class Rate:
    """Sleeps until the next tick of a timer; the timer's node must be spun in another thread.

    Args:
        timer: Timer giving the ticks (``node.create_rate`` makes one).
        context: Context whose shutdown interrupts ``sleep``.
    """

    def __init__(self, timer: Timer, *, context: Context) -> None:
        self._timer = timer
        self._context = context
        self._event = threading.Event()
        self._destroyed = False
        timer.callback = self._tick
        context.on_shutdown(self._event.set)

    def _tick(self) -> None:
        self._event.set()

    def destroy(self) -> None:
        """Stop the rate (its timer is destroyed by the node)."""
        self._destroyed = True
        self._event.set()

    def sleep(self) -> None:
        """Block until the next tick.

        Raises:
            ROSInterruptException: If the context is shut down while sleeping.
            RuntimeError: If the rate was destroyed.
        """
        if self._destroyed:
            raise RuntimeError('Rate was destroyed')
        if not self._context.ok():
            raise ROSInterruptException()
        self._event.clear()
        while not self._event.wait(0.1):
            if not self._context.ok():
                raise ROSInterruptException()
        if not self._context.ok():
            raise ROSInterruptException()
