"""The main loop every UVMS node process runs: init, spin until a signal, shut down cleanly.

rclpy's own signal handler shuts the context down from inside the signal, while callbacks
may still run: a timer then publishes on an invalid context and the process ends with a
traceback (``RCLError: Failed to publish: publisher's context is invalid``, measured on
Jazzy). So rclpy is initialised without its handlers; SIGINT and SIGTERM only set an event,
the executor spins in short turns and checks it, and the node is destroyed before the
context is shut down. The same holds before the executor exists: a signal during start-up
stops the process without a traceback, before the node is built when it came during the
imports (``uvms_common.node_entry``, the console scripts' entry).
"""

from __future__ import annotations

import faulthandler
import os
import sys
from collections.abc import Callable, Sequence

import rclpy
from rclpy.context import Context
from rclpy.executors import Executor, ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions

from uvms_common.ros_environment import ros_environment_defaults
from uvms_common.stop_event import StopEvent, active_stop_event

__all__ = ['EXECUTORS', 'SPIN_TURN_S', 'StopEvent', 'make_executor', 'run_node',
           'spin_until_stopped']

#: Executors a node process can spin on; ``UVMS_EXECUTOR`` picks one (default ``events``).
EXECUTORS = ('events', 'single')
#: Longest wait of one executor turn before the stop event is checked again (s).
SPIN_TURN_S = 0.1
#: Teardown time after which every thread's stack is written to stderr (s); below the
#: launcher's 5 s between SIGINT and SIGTERM.
TEARDOWN_REPORT_S = 4.0


def make_executor(kind: str | None = None, context: Context | None = None) -> Executor:
    """The executor a node process spins on.

    Args:
        kind: ``events`` (rclpy.experimental.EventsExecutor, the fastest here) or
            ``single`` (SingleThreadedExecutor); None reads ``UVMS_EXECUTOR``.
        context: The rclpy context (the default one if None).

    Raises:
        ValueError: An unknown kind; the message names the valid ones.
    """
    kind = kind or os.environ.get('UVMS_EXECUTOR', 'events')
    if kind == 'events':
        from rclpy.experimental import EventsExecutor

        # EventsExecutor calls faulthandler.enable() on sys.stderr, which fails where that
        # stream has no file descriptor (pytest's capture, a notebook): give it the real one.
        stderr = sys.stderr
        sys.stderr = sys.__stderr__
        try:
            return EventsExecutor(context=context)
        finally:
            sys.stderr = stderr
    if kind == 'single':
        return SingleThreadedExecutor(context=context)
    msg = f'executor {kind!r} (UVMS_EXECUTOR): valid: {", ".join(EXECUTORS)}'
    raise ValueError(msg)


def spin_until_stopped(
    executor: Executor,
    stop: StopEvent,
    finished: Callable[[], bool] = lambda: False,
    context: Context | None = None,
) -> None:
    """Spin in short turns until a stop signal, ``finished()``, or the context shuts down."""
    while not stop.is_set() and not finished() and rclpy.ok(context=context):
        executor.spin_once(timeout_sec=SPIN_TURN_S)


def run_node(
    make_node: Callable[[], Node],
    args: Sequence[str] | None,
    logger_name: str,
    startup_errors: tuple[type[Exception], ...] = (),
    finished: Callable[[Node], bool] | None = None,
) -> int:
    """Build a node and spin it until SIGINT/SIGTERM; return the process exit status.

    Args:
        make_node: Builds the node (after ``rclpy.init``).
        args: Command-line arguments for rclpy (``--ros-args ...``); None: ``sys.argv``.
        logger_name: Logger for errors that stop the node.
        startup_errors: Exceptions of a node that cannot start (invalid parameter, ...):
            logged as fatal in one line, exit status 1, no traceback.
        finished: The node's own end (e.g. the simulator reached its duration); exit 0.

    Returns:
        0 after ``finished``, a signal or an external shutdown, each ending in a clean
        shutdown (as Jazzy's demo nodes exit 0 on Ctrl-C); 1 after a start-up error or an
        error raised by a callback (logged with its type).

    A ``StopEvent`` already installed (``uvms_common.node_entry``, before the node's
    imports) is taken over, so a signal received during the imports counts too.
    """
    ros_environment_defaults()
    earlier = active_stop_event()
    stop = earlier if earlier is not None else StopEvent()
    rclpy.init(args=None if args is None else list(args),
               signal_handler_options=SignalHandlerOptions.NO)
    logger = rclpy.logging.get_logger(logger_name)
    node: Node | None = None
    executor: Executor | None = None
    status = 0
    try:
        if stop.is_set():
            return 0
        node = make_node()
        executor = make_executor()
        executor.add_node(node)
        built = node
        spin_until_stopped(executor, stop,
                           (lambda: finished(built)) if finished is not None else lambda: False)
    except startup_errors as exc:
        logger.fatal(str(exc))
        status = 1
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except Exception as exc:
        logger.fatal(f'{type(exc).__name__}: {exc}')
        status = 1
    finally:
        # A teardown stuck in the middleware (seen once in CI under load: a node that took
        # neither SIGINT nor SIGTERM and was killed) then leaves every thread's stack on
        # stderr for the bug report; the launcher's SIGTERM and SIGKILL still follow.
        faulthandler.dump_traceback_later(TEARDOWN_REPORT_S, file=sys.__stderr__ or sys.stderr)
        if executor is not None:
            executor.shutdown()
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
        faulthandler.cancel_dump_traceback_later()
        if stop is not earlier:
            stop.restore()
    return status
