"""Executors, callback groups, futures and tasks of the compat rclpy.

Each test states the behaviour of rclpy (Jazzy) it mirrors.
"""

from __future__ import annotations

import threading
import time

import pytest
import rclpy
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup, ReentrantCallbackGroup
from rclpy.context import Context
from rclpy.executors import (
    ExternalShutdownException,
    MultiThreadedExecutor,
    SingleThreadedExecutor,
)
from rclpy.impl.implementation_singleton import RCLError
from rclpy.node import Node
from rclpy.task import Future
from std_msgs.msg import Int32, String


def one_shot_timer(node: Node, log: list[str], label: str) -> None:
    """A timer that is ready at once and fires once."""
    holder: list = []

    def fire() -> None:
        log.append(label)
        holder[0].cancel()

    holder.append(node.create_timer(0.0, fire))


def callback_order(context: Context) -> list[str]:
    """Order in which a SingleThreadedExecutor runs timers and subscriptions of two nodes."""
    log: list[str] = []
    first = Node('first', context=context)
    second = Node('second', context=context)
    for node in (first, second):
        name = node.get_name()
        one_shot_timer(node, log, f'{name}.timer')
        node.create_subscription(String, f'/{name}/a', lambda m, n=name: log.append(f'{n}.a'), 10)
        node.create_subscription(String, f'/{name}/b', lambda m, n=name: log.append(f'{n}.b'), 10)
    publisher_node = Node('source', context=context)
    for topic in ('/second/b', '/first/b', '/second/a', '/first/a'):
        publisher_node.create_publisher(String, topic, 10).publish(String(data=topic))
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(first)
    executor.add_node(second)
    for _ in range(10):
        executor.spin_once(timeout_sec=0)
    executor.shutdown()
    for node in (first, second, publisher_node):
        node.destroy_node()
    return log


def test_single_threaded_order_is_timers_then_subscriptions_node_by_node(
    context: Context,
) -> None:
    """As rclpy's wait: per node (order added) its timers, then subscriptions (order created)."""
    assert callback_order(context) == [
        'first.timer', 'first.a', 'first.b', 'second.timer', 'second.a', 'second.b',
    ]


def test_single_threaded_order_is_the_same_on_every_run() -> None:
    """The same inputs give the same callback order (nodes kept in order of addition)."""
    orders = []
    for _ in range(3):
        context = Context()
        rclpy.init(args=[], context=context)
        orders.append(callback_order(context))
        context.shutdown()
    assert orders[0] == orders[1] == orders[2]


def test_each_wait_takes_one_message_per_subscription(context: Context) -> None:
    """As rclpy: one message per ready subscription per wait, so topics interleave."""
    node = Node('node', context=context)
    log: list[str] = []
    node.create_subscription(String, 'a', lambda m: log.append(m.data), 10)
    node.create_subscription(String, 'b', lambda m: log.append(m.data), 10)
    pub_a = node.create_publisher(String, 'a', 10)
    pub_b = node.create_publisher(String, 'b', 10)
    pub_a.publish(String(data='a1'))
    pub_a.publish(String(data='a2'))
    pub_b.publish(String(data='b1'))
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    for _ in range(5):
        executor.spin_once(timeout_sec=0)
    executor.shutdown()
    node.destroy_node()
    assert log == ['a1', 'b1', 'a2']


def test_multithreaded_executor_runs_reentrant_callbacks_at_the_same_time(
    context: Context,
) -> None:
    """As rclpy: callbacks of a ReentrantCallbackGroup overlap in a MultiThreadedExecutor."""
    node = Node('parallel', context=context)
    group = ReentrantCallbackGroup()
    barrier = threading.Barrier(2, timeout=5.0)
    both_inside = Future()
    passed: list[str] = []
    lock = threading.Lock()

    def meet(msg: String) -> None:
        barrier.wait()
        with lock:
            passed.append(msg.data)
            if len(passed) == 2:
                both_inside.set_result(True)

    node.create_subscription(String, 'x', meet, 10, callback_group=group)
    node.create_subscription(String, 'y', meet, 10, callback_group=group)
    node.create_publisher(String, 'x', 10).publish(String(data='x'))
    node.create_publisher(String, 'y', 10).publish(String(data='y'))
    executor = MultiThreadedExecutor(num_threads=2, context=context)
    executor.add_node(node)
    executor.spin_until_future_complete(both_inside, timeout_sec=5.0)
    executor.shutdown()
    node.destroy_node()
    assert both_inside.result() is True
    assert sorted(passed) == ['x', 'y']


def test_mutually_exclusive_callbacks_never_overlap(context: Context) -> None:
    """As rclpy: a MutuallyExclusiveCallbackGroup runs one callback at a time, even threaded."""
    node = Node('exclusive', context=context)
    group = MutuallyExclusiveCallbackGroup()
    active = [0]
    peak = [0]
    seen: list[int] = []
    lock = threading.Lock()
    done = Future()

    def work(msg: Int32) -> None:
        with lock:
            active[0] += 1
            peak[0] = max(peak[0], active[0])
        time.sleep(0.002)
        with lock:
            active[0] -= 1
            seen.append(msg.data)
            if len(seen) == 20:
                done.set_result(True)

    for topic in ('p', 'q'):
        node.create_subscription(Int32, topic, work, 20, callback_group=group)
    publishers = [node.create_publisher(Int32, topic, 20) for topic in ('p', 'q')]
    for i in range(10):
        for publisher in publishers:
            publisher.publish(Int32(data=i))
    executor = MultiThreadedExecutor(num_threads=4, context=context)
    executor.add_node(node)
    executor.spin_until_future_complete(done, timeout_sec=10.0)
    executor.shutdown()
    node.destroy_node()
    assert len(seen) == 20
    assert peak[0] == 1


def test_spin_until_future_complete_returns_with_the_result(context: Context) -> None:
    """As rclpy: spin_until_future_complete spins until a callback completes the future."""
    node = Node('futures', context=context)
    future = Future()
    node.create_timer(0.01, lambda: None if future.done() else future.set_result(42))
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    executor.spin_until_future_complete(future, timeout_sec=5.0)
    executor.shutdown()
    node.destroy_node()
    assert future.done()
    assert future.result() == 42


def test_spin_until_future_complete_gives_up_after_timeout(context: Context) -> None:
    """As rclpy: with timeout_sec the spin returns even if the future is not done."""
    node = Node('futures', context=context)
    future = Future()
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    start = time.monotonic()
    executor.spin_until_future_complete(future, timeout_sec=0.1)
    elapsed = time.monotonic() - start
    executor.shutdown()
    node.destroy_node()
    assert not future.done()
    assert 0.09 <= elapsed < 1.0


def test_future_done_callbacks_and_cancel() -> None:
    """As rclpy.task.Future: callbacks run on completion; cancel marks a pending future."""
    future = Future()
    seen: list[object] = []
    future.add_done_callback(lambda f: seen.append(f.result()))
    future.set_result('ok')
    assert future.done() and seen == ['ok']
    pending = Future()
    pending.cancel()
    assert pending.cancelled() and not pending.done()


def test_create_task_runs_a_coroutine_that_awaits_a_future(context: Context) -> None:
    """As rclpy: create_task runs a coroutine; awaiting a Future suspends it until done."""
    node = Node('tasks', context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    gate = Future()

    async def waits() -> str:
        value = await gate
        return f'got {value}'

    task = executor.create_task(waits)
    executor.spin_once(timeout_sec=0)
    assert not task.done()
    node.create_timer(0.0, lambda: None if gate.done() else gate.set_result(7))
    executor.spin_until_future_complete(task, timeout_sec=5.0)
    executor.shutdown()
    node.destroy_node()
    assert task.result() == 'got 7'


def test_guard_condition_triggered_from_another_thread_runs_its_callback(
    context: Context,
) -> None:
    """As rclpy: trigger() wakes the executor, which then calls the guard's callback."""
    node = Node('guarded', context=context)
    fired = Future()
    guard = node.create_guard_condition(lambda: fired.set_result(True))
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    threading.Timer(0.05, guard.trigger).start()
    executor.spin_until_future_complete(fired, timeout_sec=5.0)
    executor.shutdown()
    node.destroy_node()
    assert fired.result() is True


def test_exception_in_callback_propagates_out_of_spin_once(context: Context) -> None:
    """As rclpy's SingleThreadedExecutor: an exception raised by a callback leaves spin_once."""
    node = Node('failing', context=context)

    def explode(_msg: String) -> None:
        raise ValueError('bad message')

    node.create_subscription(String, 'x', explode, 10)
    node.create_publisher(String, 'x', 10).publish(String(data='x'))
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    with pytest.raises(ValueError, match='bad message'):
        executor.spin_once(timeout_sec=0)
    executor.shutdown()
    node.destroy_node()


def test_spin_raises_external_shutdown_when_context_is_shut_down_elsewhere(
    context: Context,
) -> None:
    """As rclpy: rclpy.spin blocked in a wait raises ExternalShutdownException on shutdown."""
    node = Node('spinner', context=context)
    executor = SingleThreadedExecutor(context=context)
    outcome: list[BaseException | None] = []

    def run() -> None:
        try:
            rclpy.spin(node, executor)
            outcome.append(None)
        except BaseException as e:
            outcome.append(e)

    thread = threading.Thread(target=run)
    thread.start()
    time.sleep(0.1)
    context.shutdown()
    thread.join(timeout=5.0)
    assert not thread.is_alive()
    assert isinstance(outcome[0], ExternalShutdownException)


def test_spin_once_on_shut_down_context_raises(context: Context) -> None:
    """As rclpy (wait set on an invalid context): spin_once after shutdown raises RCLError."""
    node = Node('late', context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    context.shutdown()
    with pytest.raises(RCLError, match='context is not valid'):
        executor.spin_once(timeout_sec=0)


def test_executor_shutdown_stops_spin_in_another_thread(context: Context) -> None:
    """As rclpy: Executor.shutdown() makes a running spin() return."""
    node = Node('stoppable', context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    thread = threading.Thread(target=executor.spin)
    thread.start()
    time.sleep(0.05)
    assert executor.shutdown(timeout_sec=5.0)
    thread.join(timeout=5.0)
    node.destroy_node()
    assert not thread.is_alive()


def test_module_level_spin_once_uses_the_global_executor() -> None:
    """As rclpy: rclpy.spin_once(node) spins the default context's global executor once."""
    rclpy.init(args=[])
    try:
        node = rclpy.create_node('global_user')
        received: list[str] = []
        node.create_subscription(String, 'x', lambda m: received.append(m.data), 10)
        node.create_publisher(String, 'x', 10).publish(String(data='hi'))
        rclpy.spin_once(node, timeout_sec=1.0)
        assert received == ['hi']
        assert node.executor is None
        node.destroy_node()
    finally:
        rclpy.shutdown()


def test_shutdown_from_inside_a_callback_ends_rclpy_spin() -> None:
    """As in rclpy, rclpy.shutdown() called in a callback makes rclpy.spin(node) return."""
    rclpy.init(args=[])
    node = rclpy.create_node('quitter')
    node.create_timer(0.0, rclpy.shutdown)
    outcome: list[str] = []

    def run() -> None:
        try:
            rclpy.spin(node)
            outcome.append('returned')
        except ExternalShutdownException:
            outcome.append('external shutdown')

    thread = threading.Thread(target=run)
    thread.start()
    thread.join(timeout=5.0)
    node.destroy_node()
    rclpy.try_shutdown()
    assert not thread.is_alive()
    assert outcome in (['returned'], ['external shutdown'])
