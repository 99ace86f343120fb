"""A signed span of time with nanosecond resolution (rclpy.duration)."""

from __future__ import annotations

from typing import Any

from rclpy.constants import S_TO_NS

_INT64_MAX = 2**63 - 1


class Duration:
    """A period between two time points, with nanosecond precision.

    Args:
        seconds: Span in seconds; a fractional part is kept down to the nanosecond.
        nanoseconds: Further span in nanoseconds; a fractional part is discarded.

    Raises:
        OverflowError: If the total does not fit a signed 64-bit nanosecond count.
    """

    __slots__ = ('_nanoseconds',)

    def __init__(self, *, seconds: float = 0, nanoseconds: float = 0) -> None:
        total = int(seconds * S_TO_NS) + int(nanoseconds)
        if total >= 2**63 or total < -(2**63):
            raise OverflowError('Total nanoseconds value is too large to store in C duration.')
        self._nanoseconds = total

    @property
    def nanoseconds(self) -> int:
        """Total span in nanoseconds."""
        return self._nanoseconds

    def __repr__(self) -> str:
        return f'Duration(nanoseconds={self._nanoseconds})'

    def __str__(self) -> str:
        if self._nanoseconds == _INT64_MAX:
            return 'Infinite'
        return f'{self._nanoseconds} nanoseconds'

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Duration):
            return self._nanoseconds == other._nanoseconds
        return NotImplemented

    def __ne__(self, other: object) -> bool:
        if isinstance(other, Duration):
            return self._nanoseconds != other._nanoseconds
        return NotImplemented

    def __lt__(self, other: object) -> bool:
        if isinstance(other, Duration):
            return self._nanoseconds < other._nanoseconds
        return NotImplemented

    def __le__(self, other: object) -> bool:
        if isinstance(other, Duration):
            return self._nanoseconds <= other._nanoseconds
        return NotImplemented

    def __gt__(self, other: object) -> bool:
        if isinstance(other, Duration):
            return self._nanoseconds > other._nanoseconds
        return NotImplemented

    def __ge__(self, other: object) -> bool:
        if isinstance(other, Duration):
            return self._nanoseconds >= other._nanoseconds
        return NotImplemented

    def __hash__(self) -> int:
        return hash(self._nanoseconds)

    def to_msg(self) -> Any:
        """Return the span as a ``builtin_interfaces.msg.Duration``."""
        from builtin_interfaces.msg import Duration as DurationMsg

        seconds, nanoseconds = divmod(self._nanoseconds, S_TO_NS)
        return DurationMsg(sec=seconds, nanosec=nanoseconds)

    @classmethod
    def from_msg(cls, msg: Any) -> Duration:
        """Build a Duration from a ``builtin_interfaces.msg.Duration``.

        Raises:
            TypeError: If ``msg`` is not a ``builtin_interfaces.msg.Duration``.
        """
        from builtin_interfaces.msg import Duration as DurationMsg

        if not isinstance(msg, DurationMsg):
            raise TypeError('Must pass a builtin_interfaces.msg.Duration object')
        return cls(seconds=msg.sec, nanoseconds=msg.nanosec)

    def get_c_duration(self) -> Duration:
        """Return the underlying duration (rclpy returns its C struct here)."""
        return self


#: Constant representing an infinite amount of time (``RMW_DURATION_INFINITE``).
Infinite = Duration(nanoseconds=_INT64_MAX)
