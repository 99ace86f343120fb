"""The lifecycle of init and shutdown: a Context holds one in-process ROS graph."""

from __future__ import annotations

import sys
import threading
import weakref
from collections.abc import Callable
from types import MethodType, TracebackType
from typing import TYPE_CHECKING
from weakref import WeakMethod

from rclpy._arguments import RosArguments, parse_ros_arguments

if TYPE_CHECKING:
    from rclpy._graph import Graph
    from rclpy.executors import Executor

#: Contexts initialized and not yet shut down (for the signal handlers).
_live_contexts: weakref.WeakSet[Context] = weakref.WeakSet()


class _ContextHandle:
    """Stand-in for rclpy's C context handle: usable in ``with`` blocks."""

    def __init__(self, context: Context) -> None:
        self._context = weakref.ref(context)

    def __enter__(self) -> _ContextHandle:
        return self

    def __exit__(self, *exc_info: object) -> None:
        return None

    def ok(self) -> bool:
        context = self._context()
        return context is not None and context.ok()


class Context:
    """Encapsulates the lifecycle of init and shutdown.

    All nodes created with one context share an in-process graph: a message published on a
    topic reaches every matching subscription of every node of the same context, and no other.
    Context objects should not be reused after shutdown.
    """

    def __init__(self) -> None:
        self._lock = threading.RLock()
        self._callbacks: list[WeakMethod[MethodType] | Callable[[], None]] = []
        self._initialized = False
        self._ok = False
        self._domain_id = 0
        self._handle: _ContextHandle | None = None
        self._arguments = RosArguments()
        self._executors: weakref.WeakSet[Executor] = weakref.WeakSet()
        self._graph_instance: Graph | None = None

    @property
    def handle(self) -> _ContextHandle | None:
        """Handle of the initialized context (None before init)."""
        return self._handle

    @property
    def _graph(self) -> Graph:
        if self._graph_instance is None:
            from rclpy._graph import Graph

            self._graph_instance = Graph()
        return self._graph_instance

    def destroy(self) -> None:
        """Release the context (nothing to release in process)."""

    def init(
        self,
        args: list[str] | None = None,
        *,
        initialize_logging: bool = True,
        domain_id: int | None = None,
    ) -> None:
        """Initialize ROS communications for this context.

        Args:
            args: Command-line arguments; their ``--ros-args`` sections apply to every node of
                the context. ``sys.argv`` if None.
            initialize_logging: Whether to apply ``--log-level`` and the other logging flags.
            domain_id: ROS domain id (recorded only: the graph is in-process).

        Raises:
            RuntimeError: If the context was already initialized, or ``domain_id`` is negative.
            UnknownROSArgsError: If ``--ros-args`` holds unknown flags.
            RCLError: If the ROS arguments are malformed (e.g. a bad parameter file).
        """
        with self._lock:
            if domain_id is not None and domain_id < 0:
                raise RuntimeError(f'Domain id ({domain_id}) should not be lower than zero.')
            if self._initialized:
                raise RuntimeError('Context.init() must only be called once')
            arguments = parse_ros_arguments(sys.argv if args is None else args)
            self._arguments = arguments
            self._domain_id = 0 if domain_id is None else domain_id
            self._initialized = True
            self._ok = True
            self._handle = _ContextHandle(self)
            _live_contexts.add(self)
        if initialize_logging:
            from rclpy import logging as rclpy_logging

            if arguments.default_log_level is not None:
                rclpy_logging._set_default_level(arguments.default_log_level)
            for name, level in arguments.logger_levels.items():
                rclpy_logging.set_logger_level(name, level)
            rclpy_logging._set_stdout_logs(arguments.stdout_logs)

    def ok(self) -> bool:
        """Tell whether the context is initialized and not shut down."""
        return self._ok

    def _register_executor(self, executor: Executor) -> None:
        self._executors.add(executor)

    def _wake_executors(self) -> None:
        for executor in list(self._executors):
            executor._wake()

    def _call_on_shutdown_callbacks(self) -> None:
        with self._lock:
            callbacks, self._callbacks = self._callbacks, []
        for entry in callbacks:
            callback = entry() if isinstance(entry, WeakMethod) else entry
            if callback is not None:
                callback()

    def shutdown(self) -> None:
        """Shut the context down: spinning stops and its nodes can no longer communicate.

        Raises:
            RuntimeError: If the context was never initialized.
            RCLError: If the context was already shut down (as rcl reports).
        """
        from rclpy.impl.implementation_singleton import RCLError

        with self._lock:
            if not self._initialized:
                raise RuntimeError('Context must be initialized before it can be shutdown')
            if not self._ok:
                raise RCLError('failed to shutdown: rcl_shutdown already called on the given '
                               'context')
            self._ok = False
        self._after_shutdown()

    def try_shutdown(self) -> None:
        """Shut the context down if it is initialized and not already shut down."""
        with self._lock:
            if not (self._initialized and self._ok):
                return
            self._ok = False
        self._after_shutdown()

    def _after_shutdown(self) -> None:
        _live_contexts.discard(self)
        self._wake_executors()
        self._call_on_shutdown_callbacks()

    def _remove_callback(self, weak_method: WeakMethod[MethodType]) -> None:
        with self._lock:
            if weak_method in self._callbacks:
                self._callbacks.remove(weak_method)

    def on_shutdown(self, callback: Callable[[], None]) -> None:
        """Register a callback called on shutdown (at once if already shut down).

        Raises:
            TypeError: If ``callback`` is not callable.
        """
        if not callable(callback):
            raise TypeError(f'callback should be a callable, got {type(callback)}')
        with self._lock:
            if self._initialized and not self._ok:
                callback()
                return
            if isinstance(callback, MethodType):
                self._callbacks.append(WeakMethod(callback, self._remove_callback))
            else:
                self._callbacks.append(callback)

    def get_domain_id(self) -> int:
        """Return the domain id given at init.

        Raises:
            RuntimeError: If the context is not initialized.
        """
        if not self._initialized:
            raise RuntimeError('Context must be initialized before it can have a domain id')
        return self._domain_id

    def __enter__(self) -> Context:
        self.init()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc_val: BaseException | None,
        exc_tb: TracebackType | None,
    ) -> None:
        self.try_shutdown()

    def __repr__(self) -> str:
        state = 'ok' if self._ok else ('shut down' if self._initialized else 'not initialized')
        return f'<rclpy.context.Context ({state})>'

