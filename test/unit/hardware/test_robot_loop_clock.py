"""uvms_hardware.robot_loop on simulated time: each new control period of /clock runs a period.

On its own steady timer the loop beat against the simulator's /clock (both 500 Hz, free
running): a period that found no new time computed nothing and the next one covered two, so
one state in five went unanswered at the twin stand. Now /clock runs the period as it comes.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator

import pytest
import rclpy
from rclpy.context import Context
from rclpy.node import Node
from rclpy.parameter import Parameter
from rosgraph_msgs.msg import Clock
from uvms_common.direct_topics import Bus
from uvms_common.raw_clock import take_clock_raw
from uvms_hardware.robot_loop import RobotLoop

from uvms_common import direct_topics

RATE_HZ = 500.0
PERIOD_NS = 2_000_000


def clock_cdr(stamp_ns: int) -> bytes:
    """A serialized rosgraph_msgs/Clock at ``stamp_ns`` (CDR, little endian)."""
    return struct.pack('<4siI', b'\x00\x01\x00\x00', *divmod(stamp_ns, 1_000_000_000))


@pytest.fixture
def node(request: pytest.FixtureRequest) -> Iterator[Node]:
    """A node in a context of its own, on simulated time or not (the test's parameter)."""
    context = Context()
    rclpy.init(args=[], context=context)
    made = Node('loop_clock', context=context, parameter_overrides=[
        Parameter('use_sim_time', value=request.param)])
    yield made
    made.destroy_node()
    rclpy.try_shutdown(context=context)


@pytest.mark.parametrize('node', [True], indirect=True)
def test_each_new_period_of_clock_runs_one_period_at_once(node: Node, bus: Bus) -> None:
    """A /clock a period on: one control step in its callback; within the period: none."""
    stamps: list[bytes] = []
    direct_topics.subscribe(node, Clock, '/clock', stamps.append, 10, raw=True)  # estimator
    loop = RobotLoop(bus, [node], RATE_HZ)
    loop.start(node)
    source = take_clock_raw(node)
    assert loop.clock_driven
    for k in range(1, 11):
        source.raw_clock_callback(clock_cdr(k * PERIOD_NS))
        assert loop.steps == k  # no timer spun: the /clock callback ran the period
        assert stamps[-1] == clock_cdr(k * PERIOD_NS)  # the period's time down the chain
        source.raw_clock_callback(clock_cdr(k * PERIOD_NS + PERIOD_NS // 4))
        assert loop.steps == k  # the same control period: nothing run twice
    assert loop.periods == 10
    assert '(on /clock)' in loop.summary()


@pytest.mark.parametrize('node', [False], indirect=True)
def test_on_the_wall_clock_the_steady_timer_runs_the_periods(node: Node, bus: Bus) -> None:
    """The robot itself (no simulated time): /clock is not the period."""
    loop = RobotLoop(bus, [node], RATE_HZ)
    loop.start(node)
    assert not loop.clock_driven
    take_clock_raw(node).raw_clock_callback(clock_cdr(PERIOD_NS))
    assert loop.periods == 0
