"""spin_turn: one executor turn runs every callback due in it (EventsExecutor) or one (Python)."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
import rclpy
from rclpy.context import Context
from uvms_common.node_main import make_executor, spin_turn


@pytest.fixture
def context() -> Iterator[Context]:
    """An initialised rclpy context."""
    ctx = Context()
    rclpy.init(args=[], context=ctx)
    yield ctx
    rclpy.try_shutdown(context=ctx)


def test_events_turn_runs_every_callback_due_within_it(context: Context) -> None:
    """A 5 ms timer fires many times in one 0.3 s turn of the EventsExecutor."""
    node = rclpy.create_node('turns', context=context)
    fired: list[int] = []
    node.create_timer(0.005, lambda: fired.append(1))
    executor = make_executor('events', context)
    executor.add_node(node)
    spin_turn(executor, 0.3)
    executor.shutdown()
    node.destroy_node()
    assert len(fired) > 3


def test_single_threaded_turn_runs_one_callback(context: Context) -> None:
    """The Python executor (SingleThreadedExecutor) runs one callback per turn, as spin_once."""
    node = rclpy.create_node('turns', context=context)
    fired: list[int] = []
    node.create_timer(0.005, lambda: fired.append(1))
    executor = make_executor('single', context)
    executor.add_node(node)
    spin_turn(executor, 0.3)
    executor.shutdown()
    node.destroy_node()
    assert len(fired) == 1


@pytest.mark.parametrize('kind', ['events', 'single'])
def test_callback_error_leaves_the_turn(context: Context, kind: str) -> None:
    """An exception raised by a callback reaches the caller (run_node logs it, exit 1)."""
    node = rclpy.create_node('failing', context=context)

    def fail() -> None:
        raise RuntimeError('callback failed')

    node.create_timer(0.005, fail)
    executor = make_executor(kind, context)
    executor.add_node(node)
    with pytest.raises(RuntimeError, match='callback failed'):
        spin_turn(executor, 1.0)
    executor.shutdown()
    node.destroy_node()
