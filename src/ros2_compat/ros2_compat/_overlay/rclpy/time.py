"""A point in time of a given clock type (rclpy.time)."""

from __future__ import annotations

from datetime import datetime
from typing import Any, overload

from rclpy.clock_type import ClockType
from rclpy.constants import S_TO_NS
from rclpy.duration import Duration

#: builtin_interfaces.msg.Time, imported on first use (message packages import rclpy).
_time_msg_class: Any = None


class Time:
    """A point in time: a non-negative nanosecond count since the epoch of a clock type.

    Time points are only comparable with time points of the same clock type.

    Args:
        seconds: Seconds since the epoch; a fractional part is kept down to the nanosecond.
        nanoseconds: Further nanoseconds since the epoch.
        clock_type: Clock the time point belongs to.

    Raises:
        TypeError: If ``clock_type`` is not a ClockType.
        ValueError: If ``seconds`` or ``nanoseconds`` is negative.
        OverflowError: If the total does not fit a signed 64-bit nanosecond count.
    """

    __slots__ = ('_clock_type', '_nanoseconds')

    def __init__(
        self,
        *,
        seconds: float = 0,
        nanoseconds: float = 0,
        clock_type: ClockType = ClockType.SYSTEM_TIME,
    ) -> None:
        if not isinstance(clock_type, ClockType):
            raise TypeError('Clock type must be a ClockType enum')
        if seconds < 0:
            raise ValueError('Seconds value must not be negative')
        if nanoseconds < 0:
            raise ValueError('Nanoseconds value must not be negative')
        total = int(seconds * S_TO_NS) + int(nanoseconds)
        if total >= 2**63:
            raise OverflowError('Total nanoseconds value is too large to store in C time point.')
        self._nanoseconds = total
        self._clock_type = clock_type

    @classmethod
    def _from_ns(cls, nanoseconds: int, clock_type: ClockType) -> Time:
        """Build a time point without validation (internal fast path)."""
        time = cls.__new__(cls)
        time._nanoseconds = nanoseconds
        time._clock_type = clock_type
        return time

    @property
    def nanoseconds(self) -> int:
        """Total number of nanoseconds since the clock's epoch."""
        return self._nanoseconds

    def seconds_nanoseconds(self) -> tuple[int, int]:
        """Return the time split into whole seconds and the remaining nanoseconds."""
        return divmod(self._nanoseconds, S_TO_NS)

    @property
    def clock_type(self) -> ClockType:
        """Type of the clock that produced this time point."""
        return self._clock_type

    def __repr__(self) -> str:
        return f'Time(nanoseconds={self._nanoseconds}, clock_type={self._clock_type.name})'

    def __add__(self, other: Duration) -> Time:
        if isinstance(other, Duration):
            try:
                return Time(
                    nanoseconds=self._nanoseconds + other.nanoseconds, clock_type=self._clock_type
                )
            except OverflowError as e:
                raise OverflowError('Addition leads to overflow in C storage.') from e
        return NotImplemented

    def __radd__(self, other: Duration) -> Time:
        return self.__add__(other)

    @overload
    def __sub__(self, other: Time) -> Duration: ...

    @overload
    def __sub__(self, other: Duration) -> Time: ...

    def __sub__(self, other: Time | Duration) -> Time | Duration:
        if isinstance(other, Time):
            if self._clock_type != other._clock_type:
                raise TypeError("Can't subtract times with different clock types")
            return Duration(nanoseconds=self._nanoseconds - other._nanoseconds)
        if isinstance(other, Duration):
            try:
                return Time(
                    nanoseconds=self._nanoseconds - other.nanoseconds, clock_type=self._clock_type
                )
            except ValueError as e:
                raise ValueError('Subtraction leads to negative time.') from e
        return NotImplemented

    def _check_comparable(self, other: Time) -> None:
        if self._clock_type != other._clock_type:
            raise TypeError("Can't compare times with different clock types")

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Time):
            self._check_comparable(other)
            return self._nanoseconds == other._nanoseconds
        return NotImplemented

    def __ne__(self, other: object) -> bool:
        if isinstance(other, Time):
            return not self.__eq__(other)
        return NotImplemented

    def __lt__(self, other: Time) -> bool:
        if isinstance(other, Time):
            self._check_comparable(other)
            return self._nanoseconds < other._nanoseconds
        return NotImplemented

    def __le__(self, other: Time) -> bool:
        if isinstance(other, Time):
            self._check_comparable(other)
            return self._nanoseconds <= other._nanoseconds
        return NotImplemented

    def __gt__(self, other: Time) -> bool:
        if isinstance(other, Time):
            self._check_comparable(other)
            return self._nanoseconds > other._nanoseconds
        return NotImplemented

    def __ge__(self, other: Time) -> bool:
        if isinstance(other, Time):
            self._check_comparable(other)
            return self._nanoseconds >= other._nanoseconds
        return NotImplemented

    __hash__ = None  # type: ignore[assignment]  # rclpy's Time is unhashable too

    def to_msg(self) -> Any:
        """Return the time point as a ``builtin_interfaces.msg.Time``."""
        from builtin_interfaces.msg import Time as TimeMsg

        seconds, nanoseconds = divmod(self._nanoseconds, S_TO_NS)
        return TimeMsg(sec=seconds, nanosec=nanoseconds)

    def to_datetime(self) -> datetime:
        """Return the time point as a naive local ``datetime``.

        Raises:
            TypeError: If the clock type is neither ROS_TIME nor SYSTEM_TIME.
        """
        if self._clock_type not in (ClockType.ROS_TIME, ClockType.SYSTEM_TIME):
            raise TypeError("Time object's clock type should be either ROS_TIME or SYSTEM_TIME")
        return datetime.fromtimestamp(self._nanoseconds / S_TO_NS)

    @classmethod
    def from_msg(cls, msg: Any, clock_type: ClockType = ClockType.ROS_TIME) -> Time:
        """Build a time point from a ``builtin_interfaces.msg.Time``.

        Raises:
            TypeError: If ``msg`` is not a ``builtin_interfaces.msg.Time``.
        """
        global _time_msg_class
        if _time_msg_class is None:
            from builtin_interfaces.msg import Time as TimeMsg

            _time_msg_class = TimeMsg
        if not isinstance(msg, _time_msg_class):
            raise TypeError('Must pass a builtin_interfaces.msg.Time object')
        return cls(seconds=msg.sec, nanoseconds=msg.nanosec, clock_type=clock_type)
