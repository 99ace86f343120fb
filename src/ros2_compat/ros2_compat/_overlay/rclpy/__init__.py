"""In-process implementation of the rclpy API subset used by the UVMS stack (ROS 2 Jazzy).

Importable as ``rclpy`` only when no real rclpy is found (see ``ros2_compat``). Everything
runs in one process: nodes of one Context exchange messages through an in-process graph, no
sockets are opened.

Example:
    >>> import rclpy
    >>> rclpy.init()
    >>> node = rclpy.create_node('talker')
    >>> node.destroy_node()
    >>> rclpy.shutdown()
"""

from __future__ import annotations

import threading
from typing import TYPE_CHECKING

from rclpy.context import Context
from rclpy.signals import SignalHandlerOptions, install_signal_handlers, uninstall_signal_handlers
from rclpy.task import Future
from rclpy.utilities import get_default_context, get_rmw_implementation_identifier
from rclpy.utilities import ok as ok
from rclpy.utilities import remove_ros_args as remove_ros_args
from rclpy.utilities import shutdown as _shutdown
from rclpy.utilities import try_shutdown as _try_shutdown

if TYPE_CHECKING:
    from rclpy.executors import Executor
    from rclpy.node import Node
    from rclpy.parameter import Parameter

__all__ = [
    'create_node',
    'get_default_context',
    'get_global_executor',
    'get_rmw_implementation_identifier',
    'init',
    'ok',
    'remove_ros_args',
    'shutdown',
    'spin',
    'spin_once',
    'spin_until_future_complete',
    'try_shutdown',
]

_global_executor: Executor | None = None
_executor_lock = threading.RLock()


def init(
    *,
    args: list[str] | None = None,
    context: Context | None = None,
    domain_id: int | None = None,
    signal_handler_options: SignalHandlerOptions | None = None,
) -> None:
    """Initialize ROS communications for a context (the default one if None).

    Args:
        args: Command-line arguments (``sys.argv`` if None); their ``--ros-args`` sections
            (``-p``, ``--params-file``, ``-r``, ``--log-level``) apply to every node.
        context: Context to initialize.
        domain_id: ROS domain id (recorded only).
        signal_handler_options: Signal handlers to install (all for the default context).

    Raises:
        RuntimeError: If the context was already initialized.
        UnknownROSArgsError: If ``--ros-args`` holds unknown flags.
        RCLError: If the ROS arguments are malformed (e.g. a bad parameter file).
    """
    context = get_default_context() if context is None else context
    if signal_handler_options is None:
        if context is get_default_context():
            signal_handler_options = SignalHandlerOptions.ALL
        else:
            signal_handler_options = SignalHandlerOptions.NO
    context.init(args, domain_id=domain_id)
    install_signal_handlers(signal_handler_options)


def shutdown(*, context: Context | None = None, uninstall_handlers: bool | None = None) -> None:
    """Shut down a context (the default one if None).

    Raises:
        RuntimeError: If the context was never initialized.
        RCLError: If it was already shut down.
    """
    is_default = context is None or context is get_default_context()
    _shutdown(context=context)
    if uninstall_handlers or (uninstall_handlers is None and is_default):
        uninstall_signal_handlers()


def try_shutdown(
    *, context: Context | None = None, uninstall_handlers: bool | None = None
) -> None:
    """Shut down a context if it is not already (the default one if None)."""
    is_default = context is None or context is get_default_context()
    _try_shutdown(context=context)
    if uninstall_handlers or (uninstall_handlers is None and is_default):
        uninstall_signal_handlers()


def get_global_executor() -> Executor:
    """Return the SingleThreadedExecutor used by ``rclpy.spin`` and friends."""
    global _global_executor
    with _executor_lock:
        if _global_executor is None:
            from rclpy.executors import SingleThreadedExecutor

            executor = SingleThreadedExecutor()
            _global_executor = executor

            def reset_executor() -> None:
                global _global_executor
                with _executor_lock:
                    executor.shutdown()
                    if _global_executor is executor:
                        _global_executor = None

            get_default_context().on_shutdown(reset_executor)
        return _global_executor


def create_node(
    node_name: str,
    *,
    context: Context | None = None,
    cli_args: list[str] | None = None,
    namespace: str | None = None,
    use_global_arguments: bool = True,
    enable_rosout: bool = True,
    start_parameter_services: bool = True,
    parameter_overrides: list[Parameter] | None = None,
    allow_undeclared_parameters: bool = False,
    automatically_declare_parameters_from_overrides: bool = False,
    enable_logger_service: bool = False,
) -> Node:
    """Create a Node; the arguments are those of :class:`rclpy.node.Node`."""
    from rclpy.node import Node

    return Node(
        node_name,
        context=context,
        cli_args=cli_args,
        namespace=namespace,
        use_global_arguments=use_global_arguments,
        enable_rosout=enable_rosout,
        start_parameter_services=start_parameter_services,
        parameter_overrides=parameter_overrides,
        allow_undeclared_parameters=allow_undeclared_parameters,
        automatically_declare_parameters_from_overrides=(
            automatically_declare_parameters_from_overrides
        ),
        enable_logger_service=enable_logger_service,
    )


def spin_once(
    node: Node, *, executor: Executor | None = None, timeout_sec: float | None = None
) -> None:
    """Execute one callback of ``node`` (waiting up to ``timeout_sec`` s; None: forever)."""
    executor = get_global_executor() if executor is None else executor
    try:
        executor.add_node(node)
        executor.spin_once(timeout_sec=timeout_sec)
    finally:
        executor.remove_node(node)


def spin(node: Node, executor: Executor | None = None) -> None:
    """Execute callbacks of ``node`` until its context is shut down.

    Raises:
        ExternalShutdownException: If the context is shut down while waiting for work
            (SIGINT/SIGTERM, or ``rclpy.shutdown()`` from another thread).
    """
    executor = get_global_executor() if executor is None else executor
    try:
        executor.add_node(node)
        while executor.context.ok():
            executor.spin_once()
    finally:
        executor.remove_node(node)


def spin_until_future_complete(
    node: Node,
    future: Future,
    executor: Executor | None = None,
    timeout_sec: float | None = None,
) -> None:
    """Execute callbacks of ``node`` until ``future`` is done or ``timeout_sec`` s passed."""
    executor = get_global_executor() if executor is None else executor
    try:
        executor.add_node(node)
        executor.spin_until_future_complete(future, timeout_sec)
    finally:
        executor.remove_node(node)


