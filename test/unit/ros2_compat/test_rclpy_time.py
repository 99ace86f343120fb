"""Time, Duration, clocks and timers of the compat rclpy, on wall time and on /clock time.

Each test states the behaviour of rclpy (Jazzy, with rcl's timer rules) it mirrors.
"""

from __future__ import annotations

import time

import pytest
import rclpy
from builtin_interfaces.msg import Time as TimeMsg
from rclpy.clock import Clock, ClockType, ROSClock
from rclpy.context import Context
from rclpy.duration import Duration
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.time import Time
from rosgraph_msgs.msg import Clock as ClockMsg

MS = 1_000_000


class SimClock:
    """A node publishing /clock, spun together with the node under test."""

    def __init__(self, context: Context, node: Node) -> None:
        self.node = Node('sim', context=context)
        self.publisher = self.node.create_publisher(ClockMsg, '/clock', 10)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self.executor.add_node(node)

    def advance_to(self, nanoseconds: int) -> None:
        """Publish /clock at ``nanoseconds`` and run every callback this makes ready."""
        sec, nanosec = divmod(nanoseconds, 1_000_000_000)
        self.publisher.publish(ClockMsg(clock=TimeMsg(sec=sec, nanosec=nanosec)))
        for _ in range(5):
            self.executor.spin_once(timeout_sec=0)

    def close(self) -> None:
        """Stop the executor and destroy the /clock node."""
        self.executor.shutdown()
        self.node.destroy_node()


def sim_node(context: Context, name: str = 'timed') -> Node:
    """A node with use_sim_time true from its parameter overrides."""
    return Node(
        name, context=context, parameter_overrides=[Parameter('use_sim_time', value=True)]
    )


def test_wall_timer_fires_at_its_rate(context: Context) -> None:
    """A 50 ms timer on the node clock (wall time) fires about 6 times in 0.3 s."""
    node = Node('wall', context=context)
    calls: list[float] = []
    node.create_timer(0.05, lambda: calls.append(time.monotonic()))
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    start = time.monotonic()
    while time.monotonic() - start < 0.3:
        executor.spin_once(timeout_sec=0.05)
    executor.shutdown()
    node.destroy_node()
    assert 4 <= len(calls) <= 7
    assert calls[0] - start == pytest.approx(0.05, abs=0.03)


def test_sim_time_timer_fires_exactly_once_per_period_of_clock_time(context: Context) -> None:
    """With use_sim_time, a 0.1 s timer fires when /clock crosses each period: 10 in 1 s."""
    node = sim_node(context)
    fired_at: list[int] = []
    node.create_timer(0.1, lambda: fired_at.append(node.get_clock().now().nanoseconds))
    sim = SimClock(context, node)
    for step in range(1, 101):
        sim.advance_to(step * 10 * MS)
    sim.close()
    node.destroy_node()
    assert fired_at == [k * 100 * MS for k in range(1, 11)]


def test_sim_time_timer_does_not_fire_while_clock_stands_still(context: Context) -> None:
    """With use_sim_time and no /clock progress, wall time passing fires nothing."""
    node = sim_node(context)
    calls: list[int] = []
    node.create_timer(0.01, lambda: calls.append(1))
    sim = SimClock(context, node)
    sim.advance_to(5 * MS)
    deadline = time.monotonic() + 0.1
    while time.monotonic() < deadline:
        sim.executor.spin_once(timeout_sec=0.02)
    sim.close()
    node.destroy_node()
    assert calls == []


def test_timer_that_missed_periods_fires_once_then_keeps_its_grid(context: Context) -> None:
    """As rcl_timer_call: missed periods are skipped; the next call stays on the period grid."""
    node = sim_node(context)
    fired_at: list[int] = []
    timer = node.create_timer(0.1, lambda: fired_at.append(node.get_clock().now().nanoseconds))
    sim = SimClock(context, node)
    sim.advance_to(350 * MS)
    assert fired_at == [350 * MS]
    assert timer.time_until_next_call() == 50 * MS
    sim.advance_to(400 * MS)
    sim.close()
    node.destroy_node()
    assert fired_at == [350 * MS, 400 * MS]


def test_ros_clock_reads_zero_until_first_clock_message(context: Context) -> None:
    """As rclpy's TimeSource: with use_sim_time the ROS clock is 0 until /clock arrives."""
    node = sim_node(context)
    assert node.get_clock().now().nanoseconds == 0
    assert node.get_clock().ros_time_is_active
    sim = SimClock(context, node)
    sim.advance_to(12_345 * MS)
    now = node.get_clock().now()
    sim.close()
    node.destroy_node()
    assert now.nanoseconds == 12_345 * MS
    assert now.clock_type == ClockType.ROS_TIME


def test_use_sim_time_from_command_line_enables_sim_time() -> None:
    """As rclpy: --ros-args -p use_sim_time:=true makes every node follow /clock."""
    context = Context()
    rclpy.init(args=['--ros-args', '-p', 'use_sim_time:=true'], context=context)
    try:
        node = Node('from_cli', context=context)
        assert node.get_parameter('use_sim_time').value is True
        assert node.get_clock().ros_time_is_active
        assert node.count_subscribers('/clock') == 1
        node.destroy_node()
    finally:
        context.try_shutdown()


def test_node_clock_is_wall_time_without_sim_time(context: Context) -> None:
    """As rclpy: use_sim_time defaults to False and the node clock reads system time."""
    node = Node('plain', context=context)
    assert node.get_parameter('use_sim_time').value is False
    before = time.time_ns()
    now = node.get_clock().now().nanoseconds
    after = time.time_ns()
    node.destroy_node()
    assert before <= now <= after


def test_setting_use_sim_time_at_runtime_switches_clock_and_timers(context: Context) -> None:
    """As rclpy: set_parameters(use_sim_time=True) subscribes to /clock; timers follow it."""
    node = Node('switched', context=context)
    fired_at: list[int] = []
    node.create_timer(0.1, lambda: fired_at.append(node.get_clock().now().nanoseconds))
    result = node.set_parameters([Parameter('use_sim_time', value=True)])[0]
    assert result.successful
    assert node.get_clock().ros_time_is_active
    sim = SimClock(context, node)
    sim.advance_to(5_000 * MS)
    assert node.get_clock().now().nanoseconds == 5_000 * MS
    assert fired_at == []
    sim.advance_to(5_100 * MS)
    sim.close()
    node.destroy_node()
    assert fired_at == [5_100 * MS]


def test_use_sim_time_rejects_a_non_bool(context: Context) -> None:
    """As rclpy: use_sim_time is a bool parameter; setting a string is refused."""
    node = Node('strict', context=context)
    result = node.set_parameters([Parameter('use_sim_time', value='yes')])[0]
    node.destroy_node()
    assert not result.successful
    assert 'type' in result.reason


def test_canceled_timer_does_not_fire_and_reset_restarts_its_period(context: Context) -> None:
    """As rcl: cancel() stops a timer; reset() restarts the period from now."""
    node = sim_node(context)
    calls: list[int] = []
    timer = node.create_timer(1.0, lambda: calls.append(node.get_clock().now().nanoseconds))
    sim = SimClock(context, node)
    assert timer.timer_period_ns == 1_000 * MS
    assert timer.time_until_next_call() == 1_000 * MS
    timer.cancel()
    assert timer.is_canceled()
    assert timer.time_until_next_call() is None
    sim.advance_to(2_500 * MS)
    assert calls == []
    timer.reset()
    assert not timer.is_canceled()
    assert timer.time_until_next_call() == 1_000 * MS
    assert not timer.is_ready()
    sim.advance_to(3_500 * MS)
    sim.close()
    node.destroy_node()
    assert calls == [3_500 * MS]


def test_timer_created_without_autostart_waits_for_reset(context: Context) -> None:
    """As rclpy (autostart=False): the timer starts canceled until reset()."""
    node = sim_node(context)
    timer = node.create_timer(0.1, lambda: None, autostart=False)
    assert timer.is_canceled()
    node.destroy_node()


def test_destroyed_timer_never_fires(context: Context) -> None:
    """As rclpy: destroy_timer removes the timer from execution."""
    node = sim_node(context)
    calls: list[int] = []
    timer = node.create_timer(0.1, lambda: calls.append(1))
    sim = SimClock(context, node)
    assert node.destroy_timer(timer)
    sim.advance_to(500 * MS)
    sim.close()
    node.destroy_node()
    assert calls == []


def test_backwards_clock_jump_restarts_the_period(context: Context) -> None:
    """As rcl: a backwards /clock jump beyond the last call restarts the timer from there."""
    node = sim_node(context)
    fired_at: list[int] = []
    node.create_timer(0.1, lambda: fired_at.append(node.get_clock().now().nanoseconds))
    sim = SimClock(context, node)
    sim.advance_to(1_050 * MS)
    sim.advance_to(200 * MS)
    sim.advance_to(250 * MS)
    sim.advance_to(300 * MS)
    sim.close()
    node.destroy_node()
    assert fired_at == [1_050 * MS, 300 * MS]


def test_jump_over_periods_onto_the_grid_fires_twice(context: Context) -> None:
    """As rcl_timer_call: a jump over missed periods onto the period grid gives two calls."""
    node = sim_node(context)
    fired_at: list[int] = []
    node.create_timer(0.1, lambda: fired_at.append(node.get_clock().now().nanoseconds))
    sim = SimClock(context, node)
    sim.advance_to(1_000 * MS)
    sim.advance_to(1_100 * MS)
    sim.close()
    node.destroy_node()
    assert fired_at == [1_000 * MS, 1_000 * MS, 1_100 * MS]


def test_time_plus_duration_and_time_minus_time() -> None:
    """As rclpy.time: Time + Duration is a Time; Time - Time is a Duration; same clock type."""
    t1 = Time(seconds=1, nanoseconds=500, clock_type=ClockType.ROS_TIME)
    t2 = t1 + Duration(seconds=0.5)
    assert isinstance(t2, Time)
    assert t2.nanoseconds == 1_500_000_500
    assert t2.clock_type == ClockType.ROS_TIME
    assert (t2 - t1) == Duration(nanoseconds=500_000_000)
    assert (t1 - t2).nanoseconds == -500_000_000
    assert t2 - Duration(seconds=1) == Time(nanoseconds=500_000_500, clock_type=ClockType.ROS_TIME)
    assert t1 < t2 and t2 >= t1 and t1 != t2
    assert t1.seconds_nanoseconds() == (1, 500)


def test_times_of_different_clock_types_do_not_compare() -> None:
    """As rclpy.time: comparing or subtracting times of different clock types raises TypeError."""
    ros = Time(seconds=1, clock_type=ClockType.ROS_TIME)
    system = Time(seconds=1, clock_type=ClockType.SYSTEM_TIME)
    with pytest.raises(TypeError, match='different clock types'):
        _ = ros < system
    with pytest.raises(TypeError, match='different clock types'):
        _ = ros - system


def test_time_rejects_negative_values() -> None:
    """As rclpy.time: negative seconds or nanoseconds raise ValueError."""
    with pytest.raises(ValueError, match='Seconds value must not be negative'):
        Time(seconds=-1)
    with pytest.raises(ValueError, match='Nanoseconds value must not be negative'):
        Time(nanoseconds=-1)


def test_time_message_round_trip() -> None:
    """As rclpy.time: to_msg splits sec/nanosec; from_msg makes a ROS_TIME time point."""
    t = Time(seconds=3, nanoseconds=250, clock_type=ClockType.ROS_TIME)
    msg = t.to_msg()
    assert (msg.sec, msg.nanosec) == (3, 250)
    back = Time.from_msg(msg)
    assert back == t
    assert Duration.from_msg(Duration(seconds=-1.5).to_msg()) == Duration(seconds=-1.5)


def test_clock_with_ros_time_type_is_a_ros_clock() -> None:
    """As rclpy.clock: Clock(clock_type=ROS_TIME) returns a ROSClock."""
    clock = Clock(clock_type=ClockType.ROS_TIME)
    assert isinstance(clock, ROSClock)
    steady = Clock(clock_type=ClockType.STEADY_TIME)
    assert steady.now().clock_type == ClockType.STEADY_TIME
    assert steady.now() <= steady.now()
