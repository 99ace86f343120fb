"""The clock types of rcl: which time source a clock or time point uses."""

from __future__ import annotations

from enum import IntEnum


class ClockType(IntEnum):
    """Time source of a clock (values as ``rcl_clock_type_t``)."""

    UNINITIALIZED = 0
    ROS_TIME = 1
    SYSTEM_TIME = 2
    STEADY_TIME = 3
