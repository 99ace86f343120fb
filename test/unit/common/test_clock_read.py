"""clock_read: the hot paths' clock reads give what ``Clock.now()`` gives."""

from __future__ import annotations

from rclpy.clock import Clock, ClockType, ROSClock
from rclpy.time import Time
from uvms_common.clock_read import now_ns, steady_ns
from uvms_hardware.device_clock import DeviceClock


def test_a_simulated_clock_reads_the_time_it_was_set_to() -> None:
    """Under /clock (a ROS time override) both reads give the stamp set, to the nanosecond."""
    clock = ROSClock()
    clock._set_ros_time_is_active(True)
    clock.set_ros_time_override(Time(nanoseconds=1_700_000_000_123_456_789,
                                     clock_type=ClockType.ROS_TIME))
    assert now_ns(clock) == clock.now().nanoseconds == 1_700_000_000_123_456_789


def test_steady_reads_are_the_steady_clock_of_rclpy() -> None:
    """``steady_ns`` and a bridge's ``now_s`` lie between two reads of rclpy's steady clock."""
    steady = Clock(clock_type=ClockType.STEADY_TIME)
    device = DeviceClock.__new__(DeviceClock)  # now_s reads no node
    device.clock = steady
    before = steady.now().nanoseconds
    ns, s = steady_ns(), device.now_s()
    after = steady.now().nanoseconds
    assert before <= ns <= after and before * 1e-9 <= s <= after * 1e-9
    assert before <= now_ns(steady) <= steady.now().nanoseconds
