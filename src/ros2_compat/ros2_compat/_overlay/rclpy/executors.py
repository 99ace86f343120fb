"""Executors: run the callbacks of nodes' timers, subscriptions and guard conditions.

The order of ready work is rclpy's: pending tasks (newest first), then node by node in the
order nodes were added, each node's timers, then its subscriptions, then its guard conditions,
in creation order. A subscription hands over one message (its oldest) per wait, so messages are
processed in FIFO order. rclpy keeps nodes in a set; keeping them in order of addition makes
the SingleThreadedExecutor deterministic.
"""

from __future__ import annotations

import inspect
import os
import threading
import time as _time
from collections import deque
from collections.abc import Callable
from concurrent.futures import Future as _PoolFuture
from concurrent.futures import ThreadPoolExecutor
from typing import TYPE_CHECKING, Any

from rclpy.context import Context
from rclpy.impl.implementation_singleton import RCLError
from rclpy.task import Future, Task
from rclpy.utilities import get_default_context, timeout_sec_to_nsec

if TYPE_CHECKING:
    from rclpy.node import Node

__all__ = [
    'ConditionReachedException',
    'Executor',
    'ExternalShutdownException',
    'MultiThreadedExecutor',
    'ShutdownException',
    'SingleThreadedExecutor',
    'TimeoutException',
    'TimeoutObject',
]


class ExternalShutdownException(Exception):  # noqa: N818 (rclpy's name)
    """Context has been shutdown."""


class ShutdownException(Exception):  # noqa: N818 (rclpy's name)
    """Signal that executor was shut down."""


class TimeoutException(Exception):  # noqa: N818 (rclpy's name)
    """Signal that a timeout occurred."""


class ConditionReachedException(Exception):  # noqa: N818 (rclpy's name)
    """Future has been completed."""


class TimeoutObject:
    """Use timeout object to save timeout."""

    def __init__(self, timeout: float) -> None:
        self._timeout = timeout

    @property
    def timeout(self) -> float:
        """Remaining timeout in seconds."""
        return self._timeout

    @timeout.setter
    def timeout(self, timeout: float) -> None:
        self._timeout = timeout


_SUBSCRIPTION = 0
_TIMER = 1
_GUARD = 2
_TASK = 3


def _never() -> bool:
    return False


#: The executor whose callback the current thread is running, if any.
_running = threading.local()


def _invalid_context_error() -> RCLError:
    return RCLError(
        'failed to initialize wait set: the given context is not valid, either rclpy.init() '
        'was not called or rclpy.shutdown() was called'
    )


class Executor:
    """Base of the executors: holds nodes and finds the work that is ready.

    Args:
        context: Context whose nodes are spun (the default context if None).
    """

    def __init__(self, *, context: Context | None = None) -> None:
        self._context = get_default_context() if context is None else context
        self._nodes: dict[Node, None] = {}
        self._node_list: tuple[Node, ...] = ()
        self._nodes_lock = threading.RLock()
        self._cond = threading.Condition(threading.RLock())
        self._wake_pending = False
        self._waiting = False
        self._is_shutdown = False
        self._tasks: list[tuple[Task, Any, Any]] = []
        self._tasks_lock = threading.RLock()
        self._ready: deque[tuple[Any, Any, int]] = deque()
        self._last_args: tuple[Any, ...] | None = None
        self._work_count = 0
        # A plain lock (C-level context manager) guards the count; the condition on it is
        # notified only while shutdown() waits on it.
        self._work_lock = threading.Lock()
        self._work_cond = threading.Condition(self._work_lock)
        self._shutdown_waiting = False
        self._context._register_executor(self)

    @property
    def context(self) -> Context:
        """Context of the executor."""
        return self._context

    def create_task(self, callback: Callable[..., Any], *args: Any, **kwargs: Any) -> Task:
        """Run ``callback(*args, **kwargs)`` (a function or coroutine) while spinning.

        Returns:
            A Task (a Future) completed with the callback's result.
        """
        task = Task(callback, args, kwargs, executor=self)
        with self._tasks_lock:
            self._tasks.append((task, None, None))
        self._wake()
        return task

    def shutdown(self, timeout_sec: float | None = None) -> bool:
        """Stop executing callbacks; wait for running ones to finish.

        Args:
            timeout_sec: Seconds to wait for running callbacks (None: as long as needed).

        Returns:
            True if the executor shut down within the timeout.
        """
        self._is_shutdown = True
        self._wake()
        deadline = None if timeout_sec is None else _time.monotonic() + timeout_sec
        # A callback shutting its own executor down (rclpy.shutdown() in a callback) must not
        # wait for itself.
        own_work = 1 if getattr(_running, 'executor', None) is self else 0
        with self._work_cond:
            self._shutdown_waiting = True
            try:
                while self._work_count > own_work:
                    remaining = None if deadline is None else deadline - _time.monotonic()
                    if remaining is not None and remaining <= 0:
                        return False
                    self._work_cond.wait(remaining)
            finally:
                self._shutdown_waiting = False
        with self._nodes_lock:
            for node in self._nodes:
                if node._executor is self:
                    node._executor = None
            self._nodes.clear()
            self._node_list = ()
        self._ready.clear()
        self._last_args = None
        return True

    def add_node(self, node: Node) -> bool:
        """Add a node whose callbacks this executor runs (it leaves any previous executor).

        Returns:
            True if the node was added, False if it was already there.
        """
        with self._nodes_lock:
            if node in self._nodes:
                return False
            self._nodes[node] = None
            self._node_list = tuple(self._nodes)
        node.executor = self
        self._wake()
        return True

    def remove_node(self, node: Node) -> None:
        """Stop running a node's callbacks."""
        with self._nodes_lock:
            if node not in self._nodes:
                return
            del self._nodes[node]
            self._node_list = tuple(self._nodes)
            if node._executor is self:
                node._executor = None
        self._wake()

    def get_nodes(self) -> list[Node]:
        """Return the nodes in order of addition."""
        return list(self._node_list)

    def wake(self) -> None:
        """Wake the executor if it is waiting for work."""
        self._wake()

    def _wake(self) -> None:
        self._wake_pending = True
        if self._waiting:
            with self._cond:
                self._cond.notify_all()

    def _wait(self, timeout_s: float | None) -> None:
        with self._cond:
            self._waiting = True
            try:
                if not self._wake_pending:
                    self._cond.wait(timeout_s)
            finally:
                self._waiting = False

    def spin(self) -> None:
        """Execute callbacks until the context is shut down or the executor is."""
        while self._context.ok() and not self._is_shutdown:
            self.spin_once()

    def spin_once(self, timeout_sec: float | None = None) -> None:
        """Wait for work (up to ``timeout_sec`` s; None: forever) and execute one callback.

        Raises:
            ExternalShutdownException: If the context is shut down while waiting.
            RCLError: If the context is not initialized or already shut down.
            Exception: Whatever the callback raised.
        """
        raise NotImplementedError()

    def spin_until_future_complete(
        self, future: Future, timeout_sec: float | None = None
    ) -> None:
        """Execute callbacks until ``future`` is done or ``timeout_sec`` s have passed."""
        future.add_done_callback(lambda _future: self._wake())
        if timeout_sec is None or timeout_sec < 0:
            while self._context.ok() and not future.done() and not self._is_shutdown:
                self._spin_once_until_future_complete(future, timeout_sec)
        else:
            end = _time.monotonic() + timeout_sec
            timeout_left = TimeoutObject(timeout_sec)
            while self._context.ok() and not future.done() and not self._is_shutdown:
                self._spin_once_until_future_complete(future, timeout_left)
                now = _time.monotonic()
                if now >= end:
                    return
                timeout_left.timeout = end - now

    def spin_once_until_future_complete(
        self, future: Future, timeout_sec: float | TimeoutObject | None = None
    ) -> None:
        """Execute one callback, returning early once ``future`` is done."""
        self._spin_once_until_future_complete(future, timeout_sec)

    def _spin_once_until_future_complete(
        self, future: Future, timeout_sec: float | TimeoutObject | None = None
    ) -> None:
        raise NotImplementedError()

    # -- finding ready work -------------------------------------------------------------

    def can_execute(self, entity: Any) -> bool:
        """Tell whether an entity's callback could start now."""
        return not entity._executor_event and entity.callback_group.can_execute(entity)

    def _collect(self, nodes: tuple[Node, ...] | list[Node]) -> int | None:
        """Queue the ready work of ``nodes``; return ns until the next timer (None: unknown)."""
        ready = self._ready
        wait_ns: int | None = None
        for node in nodes:
            for timer in node._timers:
                if timer._canceled or timer._executor_event:
                    continue
                if timer._ready():
                    if timer.callback_group.can_execute(timer):
                        ready.append((timer, node, _TIMER))
                else:
                    remaining = timer._wait_ns()
                    if remaining is not None and (wait_ns is None or remaining < wait_ns):
                        wait_ns = remaining
            for subscription in node._subscriptions:
                if (
                    subscription._queue
                    and not subscription._executor_event
                    and subscription.callback_group.can_execute(subscription)
                ):
                    ready.append((subscription, node, _SUBSCRIPTION))
            for guard in node._guards:
                if (
                    guard._triggered
                    and not guard._executor_event
                    and guard.callback_group.can_execute(guard)
                ):
                    ready.append((guard, node, _GUARD))
        return wait_ns

    def _collect_tasks(self, nodes: tuple[Node, ...] | list[Node]) -> None:
        with self._tasks_lock:
            self._tasks = [entry for entry in self._tasks if not entry[0].done()]
            tasks = list(self._tasks)
        for task, _entity, node in reversed(tasks):
            if (
                not task.executing()
                and not task.done()
                and task._ready()
                and (node is None or node in nodes)
            ):
                self._ready.append((task, node, _TASK))

    def _next_ready(
        self,
        timeout_sec: float | TimeoutObject | None = None,
        nodes: list[Node] | None = None,
        condition: Callable[[], bool] = _never,
    ) -> tuple[Any, Any, int]:
        """Return the next ready (entity, node, kind), waiting for work if there is none."""
        args = (timeout_sec, nodes, condition)
        if args != self._last_args:
            self._last_args = args
            self._ready.clear()
        ready = self._ready
        while ready:
            entity, node, kind = ready.popleft()
            if kind == _TASK or entity.callback_group.can_execute(entity):
                return entity, node, kind
        if isinstance(timeout_sec, TimeoutObject):
            timeout_sec = timeout_sec.timeout
        timeout_ns = timeout_sec_to_nsec(timeout_sec)
        deadline = None if timeout_ns < 0 else _time.monotonic_ns() + timeout_ns
        if not self._context._ok:
            raise _invalid_context_error()
        while not self._is_shutdown and not condition():
            nodes_to_use = self._node_list if nodes is None else nodes
            self._wake_pending = False
            if self._tasks:
                self._collect_tasks(nodes_to_use)
            wait_ns = self._collect(nodes_to_use)
            while ready:
                entity, node, kind = ready.popleft()
                if kind == _TASK or entity.callback_group.can_execute(entity):
                    return entity, node, kind
            if deadline is not None:
                remaining = deadline - _time.monotonic_ns()
                if remaining <= 0:
                    raise TimeoutException()
                wait_ns = remaining if wait_ns is None else min(wait_ns, remaining)
            self._wait(None if wait_ns is None else max(wait_ns, 0) / 1e9)
            if self._is_shutdown:
                raise ShutdownException()
            if not self._context._ok:
                raise ExternalShutdownException()
        if self._is_shutdown:
            raise ShutdownException()
        raise ConditionReachedException()

    def wait_for_ready_callbacks(
        self,
        timeout_sec: float | TimeoutObject | None = None,
        nodes: list[Node] | None = None,
        condition: Callable[[], bool] = _never,
    ) -> tuple[Task, Any, Any]:
        """Wait for work and return ``(handler, entity, node)``; calling handler runs it.

        Raises:
            TimeoutException: If nothing became ready within the timeout.
            ShutdownException: If the executor was shut down.
            ExternalShutdownException: If the context was shut down while waiting.
            ConditionReachedException: If ``condition()`` became true.
        """
        entity, node, kind = self._next_ready(timeout_sec, nodes, condition)
        if kind == _TASK:
            return entity, None, node
        handler = Task(self._execute, (entity, node, kind), executor=self)
        return handler, entity, node

    # -- running work ----------------------------------------------------------------------

    def _begin_work(self) -> None:
        with self._work_lock:
            self._work_count += 1

    def _end_work(self) -> None:
        with self._work_lock:
            self._work_count -= 1
            if not self._work_count and self._shutdown_waiting:
                self._work_cond.notify_all()

    def _take(self, entity: Any, kind: int) -> tuple[bool, Any]:
        """Take the work of an entity: (whether there is a callback to run, its argument)."""
        if kind == _SUBSCRIPTION:
            try:
                return True, entity._queue.popleft()
            except IndexError:
                return False, None
        if kind == _TIMER:
            return entity._call(), None
        entity._triggered = False
        return True, None

    def _run_callback(self, entity: Any, kind: int, argument: Any) -> None:
        callback = entity.callback
        if callback is None:
            return
        previous = getattr(_running, 'executor', None)
        _running.executor = self
        try:
            result = callback(argument) if kind == _SUBSCRIPTION else callback()
        finally:
            _running.executor = previous
        if result is not None:
            self._await_result(entity, result)

    def _await_result(self, entity: Any, result: Any) -> None:
        """Run a coroutine a callback returned as a task (other results are ignored)."""
        if inspect.iscoroutine(result):
            task = Task(result, executor=self)
            task()
            if not task.done():
                with self._tasks_lock:
                    self._tasks.append((task, entity, None))
            elif task.exception() is not None:
                raise task.exception()  # type: ignore[misc]

    def _execute(self, entity: Any, node: Any, kind: int) -> None:
        """Run one piece of ready work in the calling thread."""
        if kind == _TASK:
            entity()
            if entity.done() and entity.exception() is not None:
                raise entity.exception()
            return
        group = entity.callback_group
        if not group.beginning_execution(entity):
            return
        with self._work_lock:
            self._work_count += 1
        try:
            if kind == _SUBSCRIPTION:
                # The common case, inlined (_take and _run_callback): one message per wait.
                queue = entity._queue
                callback = entity.callback
                if queue and callback is not None:
                    msg = queue.popleft()
                    previous = getattr(_running, 'executor', None)
                    _running.executor = self
                    try:
                        result = callback(msg)
                    finally:
                        _running.executor = previous
                    if result is not None:
                        self._await_result(entity, result)
                elif queue:
                    queue.popleft()
            else:
                has_work, argument = self._take(entity, kind)
                if has_work:
                    self._run_callback(entity, kind, argument)
        finally:
            group.ending_execution(entity)
            self._end_work()


class SingleThreadedExecutor(Executor):
    """Runs callbacks in the thread that spins, one at a time, in a deterministic order."""

    def _spin_once_impl(
        self,
        timeout_sec: float | TimeoutObject | None = None,
        wait_condition: Callable[[], bool] = _never,
    ) -> None:
        try:
            entity, node, kind = self._next_ready(timeout_sec, None, wait_condition)
        except (ShutdownException, TimeoutException, ConditionReachedException):
            return
        self._execute(entity, node, kind)

    def spin_once(self, timeout_sec: float | None = None) -> None:
        """Wait for work (up to ``timeout_sec`` s; None: forever) and execute one callback.

        Raises:
            ExternalShutdownException: If the context is shut down while waiting.
            RCLError: If the context is not initialized or already shut down.
            Exception: Whatever the callback raised.
        """
        self._spin_once_impl(timeout_sec)

    def _spin_once_until_future_complete(
        self, future: Future, timeout_sec: float | TimeoutObject | None = None
    ) -> None:
        self._spin_once_impl(timeout_sec, future.done)


class MultiThreadedExecutor(Executor):
    """Runs callbacks in a thread pool: callbacks of a reentrant group may overlap.

    Callbacks of one mutually exclusive group (the default group of a node) never overlap.

    Args:
        num_threads: Worker threads (the number of CPUs if None).
        context: Context whose nodes are spun (the default context if None).

    Raises:
        ValueError: If ``num_threads`` is not positive.
    """

    def __init__(self, num_threads: int | None = None, *, context: Context | None = None) -> None:
        super().__init__(context=context)
        if num_threads is None:
            num_threads = os.cpu_count() or 2
        if num_threads <= 0:
            raise ValueError(f'num_threads must be greater than 0, got {num_threads}')
        self._pool = ThreadPoolExecutor(num_threads, thread_name_prefix='rclpy_mte')
        self._futures: list[_PoolFuture[None]] = []

    def _run_in_worker(self, entity: Any, node: Any, kind: int) -> None:
        if kind == _TASK:
            try:
                entity()
            finally:
                self._wake()
            if entity.done() and entity.exception() is not None:
                raise entity.exception()
            return
        group = entity.callback_group
        if not group.beginning_execution(entity):
            entity._executor_event = False
            self._end_work()
            self._wake()
            return
        try:
            has_work, argument = self._take(entity, kind)
            entity._executor_event = False
            self._wake()
            if has_work:
                self._run_callback(entity, kind, argument)
        finally:
            group.ending_execution(entity)
            self._end_work()
            self._wake()

    def _spin_once_impl(
        self,
        timeout_sec: float | TimeoutObject | None = None,
        wait_condition: Callable[[], bool] = _never,
    ) -> None:
        try:
            entity, node, kind = self._next_ready(timeout_sec, None, wait_condition)
        except (
            ExternalShutdownException,
            ShutdownException,
            TimeoutException,
            ConditionReachedException,
        ):
            pass
        else:
            if kind != _TASK:
                entity._executor_event = True
                self._begin_work()
            else:
                entity._executing = True
            try:
                self._futures.append(self._pool.submit(self._run_in_worker, entity, node, kind))
            except RuntimeError:
                if kind != _TASK:
                    entity._executor_event = False
                    self._end_work()
                raise
        for future in self._futures[:]:
            if future.done():
                self._futures.remove(future)
                future.result()

    def spin_once(self, timeout_sec: float | None = None) -> None:
        """Wait for work and hand one callback to a worker thread.

        Raises:
            RCLError: If the context is not initialized or already shut down.
            Exception: Whatever an earlier callback raised in a worker.
        """
        self._spin_once_impl(timeout_sec)

    def _spin_once_until_future_complete(
        self, future: Future, timeout_sec: float | TimeoutObject | None = None
    ) -> None:
        self._spin_once_impl(timeout_sec, future.done)

    def shutdown(self, timeout_sec: float | None = None, wait_for_threads: bool = True) -> bool:
        """Stop executing callbacks and stop the worker threads.

        Returns:
            True if running callbacks finished within the timeout.
        """
        success = super().shutdown(timeout_sec)
        self._pool.shutdown(wait=wait_for_threads)
        return success
