"""Futures and tasks: results that complete later, and callbacks or coroutines run by executors."""

from __future__ import annotations

import inspect
import sys
import threading
import weakref
from collections.abc import Callable, Coroutine, Generator
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from rclpy.executors import Executor


class Future:
    """The result of an operation that completes later (rclpy.task.Future).

    Args:
        executor: Executor that runs the done callbacks; without one they run at once, in the
            thread that completes the future.
    """

    def __init__(self, *, executor: Executor | None = None) -> None:
        self._state = 'PENDING'
        self._result: Any = None
        self._exception: BaseException | None = None
        self._exception_fetched = False
        self._callbacks: list[Callable[[Future], None]] = []
        self._lock = threading.RLock()
        self._executor: weakref.ref[Executor] | None = None
        self._set_executor(executor)

    def __del__(self) -> None:
        if self._exception is not None and not self._exception_fetched:
            print(
                'The following exception was never retrieved: ' + str(self._exception),
                file=sys.stderr,
            )

    def __await__(self) -> Generator[Future, None, Any]:
        while self._state == 'PENDING':
            yield self
        return self.result()

    def cancel(self) -> None:
        """Request cancellation; a pending future becomes cancelled."""
        with self._lock:
            if self._state == 'PENDING':
                self._state = 'CANCELLED'
            else:
                return
        self._schedule_or_invoke_done_callbacks()

    def cancelled(self) -> bool:
        """Tell whether the future was cancelled."""
        return self._state == 'CANCELLED'

    def done(self) -> bool:
        """Tell whether the future has a result or an exception."""
        return self._state == 'FINISHED'

    def result(self) -> Any:
        """Return the result (None if not done); raise the exception if one was set."""
        if self._exception is not None:
            self._exception_fetched = True
            raise self._exception
        return self._result

    def exception(self) -> BaseException | None:
        """Return the exception set on the future, if any."""
        self._exception_fetched = True
        return self._exception

    def set_result(self, result: Any) -> None:
        """Complete the future with a result and run the done callbacks."""
        with self._lock:
            self._result = result
            self._state = 'FINISHED'
        self._schedule_or_invoke_done_callbacks()

    def set_exception(self, exception: BaseException) -> None:
        """Complete the future with an exception and run the done callbacks."""
        with self._lock:
            self._exception = exception
            self._exception_fetched = False
            self._state = 'FINISHED'
        self._schedule_or_invoke_done_callbacks()

    def _schedule_or_invoke_done_callbacks(self) -> None:
        with self._lock:
            callbacks, self._callbacks = self._callbacks, []
        executor = self._executor() if self._executor is not None else None
        for callback in callbacks:
            if executor is not None:
                executor.create_task(callback, self)
            else:
                callback(self)

    def _set_executor(self, executor: Executor | None) -> None:
        self._executor = None if executor is None else weakref.ref(executor)

    def add_done_callback(self, callback: Callable[[Future], None]) -> None:
        """Call ``callback(future)`` when the future completes (at once if it already has)."""
        invoke = False
        with self._lock:
            if self._state != 'PENDING':
                invoke = True
            else:
                self._callbacks.append(callback)
        if invoke:
            executor = self._executor() if self._executor is not None else None
            if executor is not None:
                executor.create_task(callback, self)
            else:
                callback(self)

    def remove_done_callback(self, callback: Callable[[Future], None]) -> bool:
        """Forget a done callback; return whether it was registered."""
        with self._lock:
            if callback in self._callbacks:
                self._callbacks.remove(callback)
                return True
        return False


class Task(Future):
    """A callable or coroutine run by an executor, whose result is the handler's.

    Args:
        handler: A function, a coroutine function, or a coroutine object.
        args: Positional arguments for a function handler.
        kwargs: Keyword arguments for a function handler.
        executor: Executor that runs the task.
    """

    def __init__(
        self,
        handler: Callable[..., Any] | Coroutine[Any, Any, Any],
        args: tuple[Any, ...] | list[Any] | None = None,
        kwargs: dict[str, Any] | None = None,
        executor: Executor | None = None,
    ) -> None:
        super().__init__(executor=executor)
        self._handler: Any = handler
        self._args = tuple(args or ())
        self._kwargs = dict(kwargs or {})
        if inspect.iscoroutinefunction(handler):
            self._handler = handler(*self._args, **self._kwargs)
            self._args = ()
            self._kwargs = {}
        self._executing = False
        self._awaiting: Future | None = None
        self._task_lock = threading.Lock()

    def __call__(self) -> None:
        """Run the handler, or advance the coroutine to its next suspension."""
        if self._state != 'PENDING' or not self._task_lock.acquire(blocking=False):
            return
        try:
            if self._state != 'PENDING':
                return
            self._executing = True
            if inspect.iscoroutine(self._handler):
                try:
                    awaited = self._handler.send(None)
                except StopIteration as e:
                    self.set_result(e.value)
                    self._complete_task()
                except Exception as e:
                    self.set_exception(e)
                    self._complete_task()
                else:
                    self._await(awaited)
            else:
                try:
                    self.set_result(self._handler(*self._args, **self._kwargs))
                except Exception as e:
                    self.set_exception(e)
                self._complete_task()
        finally:
            self._executing = False
            self._task_lock.release()

    def _await(self, awaited: Any) -> None:
        """Remember what the coroutine waits for; wake the executor when it completes."""
        if isinstance(awaited, Future) and not awaited.done():
            self._awaiting = awaited
            awaited.add_done_callback(self._wake_executor)
        else:
            self._awaiting = None

    def _wake_executor(self, _future: Future) -> None:
        executor = self._executor() if self._executor is not None else None
        if executor is not None:
            executor._wake()

    def _ready(self) -> bool:
        """Tell whether a run would make progress (not waiting on a pending future)."""
        awaiting = self._awaiting
        return awaiting is None or awaiting._state != 'PENDING'

    def _complete_task(self) -> None:
        if inspect.iscoroutine(self._handler):
            self._handler.close()
        self._handler = None
        self._args = ()
        self._kwargs = {}

    def executing(self) -> bool:
        """Tell whether the task is running right now."""
        return self._executing
