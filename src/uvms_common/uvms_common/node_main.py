"""The main loop every UVMS node process runs: init, spin until a signal, shut down cleanly.

rclpy's own signal handler shuts the context down from inside the signal, while callbacks
may still run: a timer then publishes on an invalid context and the process ends with a
traceback (``RCLError: Failed to publish: publisher's context is invalid``, measured on
Jazzy). So rclpy is initialised without its handlers; SIGINT and SIGTERM only set an event,
the executor spins in short turns and checks it, and the node is destroyed before the
context is shut down. The same holds before the executor exists: a signal during start-up
stops the process without a traceback, before the node is built when it came during the
imports (``uvms_common.node_entry``, the console scripts' entry), at once when it came while
the node was being built (model, kernels).

The teardown is bounded: the node's output is closed first (the recorder's MCAP file), then
the middleware teardown gets ``TEARDOWN_GRACE_S``; a teardown still running then (rclpy's
``destroy_node`` has been seen to hang) writes every thread's stack to stderr and ends the
process with the status it would have had, well before the launcher's SIGTERM and SIGKILL.

In a node process (``uvms_common.node_entry``, which ends the process as soon as ``main``
returns) the middleware's teardown is not run at all (issue 48): the node's own work at its
end still is (its ``destroy_node`` override: goals cancelled, devices put back, files
closed), with rclpy's entity destruction made a no-op (``middleware_teardown_skipped``),
then the reliable publishers get ``ACK_WAIT_S`` to have their data acknowledged, and the
process leaves. A stop seen in CI ended with faulthandler's backstop (status 1) in
``ActionClient.destroy`` after the mission had succeeded: a teardown that blocks holding the
GIL; the process's end frees the same resources without that risk. Peers forget the
vanished participant after its lease (``fastdds_loopback.xml``).
"""

from __future__ import annotations

import contextlib
import faulthandler
import os
import sys
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from typing import TypeVar

import rclpy
from rclpy.context import Context
from rclpy.executors import Executor, ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions

from uvms_common import process_stats
from uvms_common.node_construction import kept_on_failure
from uvms_common.node_entry import end_unbuilt, flush_output, process_ends_after_main
from uvms_common.realtime import process_periods
from uvms_common.ros_environment import ros_environment_defaults
from uvms_common.scheduling import Scheduling, apply_scheduling, parse_cpus
from uvms_common.stop_event import StopEvent, active_stop_event

__all__ = ['ACK_WAIT_S', 'EXECUTORS', 'SPIN_TURN_S', 'TEARDOWN_BACKSTOP_S', 'TEARDOWN_GRACE_S',
           'StopEvent', 'TeardownDeadline', 'make_executor', 'middleware_teardown_skipped',
           'profiled', 'run_node', 'schedule_process', 'spin_until_stopped', 'wait_for_acks']

#: The node class a process runs.
N = TypeVar('N', bound=Node)

#: Executors a node process can spin on; ``UVMS_EXECUTOR`` picks one (default ``events``).
EXECUTORS = ('events', 'single')
#: Longest wait of one executor turn before the stop event is checked again (s).
SPIN_TURN_S = 0.1
#: Time the middleware teardown (executor, node, context) gets once the node's output is
#: closed (s); a normal one takes tens of milliseconds. After it the process ends itself: a
#: stop stays within 2 s of the signal, far below the launcher's 5 s before SIGTERM.
TEARDOWN_GRACE_S = 1.0
#: Longest a node process leaving without the middleware's teardown waits for its reliable
#: publishers' data to be acknowledged (s, over all of them).
ACK_WAIT_S = 0.3
#: Further time after which faulthandler's own thread dumps the stacks and exits (status 1):
#: for a teardown stuck while holding the GIL, where no Python thread runs any more (s).
TEARDOWN_BACKSTOP_S = 1.0


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


@contextlib.contextmanager
def profiled(name: str) -> Iterator[None]:
    """Profile the block with cProfile when ``UVMS_PROFILE`` names a directory.

    The statistics go to ``<UVMS_PROFILE>/<name>-<pid>.prof`` (read them with ``pstats`` or
    ``bench/profile_nodes.py``). Times are the CPU time of the spinning thread
    (``time.thread_time``), not wall time: an executor waiting for work counts nothing, and
    the middleware's own threads (Fast DDS receive and event threads) are not in it. Unset
    (the default), nothing is profiled.
    """
    directory = os.environ.get('UVMS_PROFILE')
    if not directory:
        yield
        return
    import cProfile

    profile = cProfile.Profile(time.thread_time)
    profile.enable()
    try:
        yield
    finally:
        profile.disable()
        os.makedirs(directory, exist_ok=True)
        profile.dump_stats(os.path.join(directory, f'{name}-{os.getpid()}.prof'))


def spin_until_stopped(
    executor: Executor,
    stop: StopEvent,
    finished: Callable[[], bool] = lambda: False,
    context: Context | None = None,
) -> None:
    """Spin in short turns until a stop signal, ``finished()``, or the context shuts down."""
    while not stop.is_set() and not finished() and rclpy.ok(context=context):
        executor.spin_once(timeout_sec=SPIN_TURN_S)


#: Longest a stopping node spends taking what had already arrived (``drain_taken``) (s).
#: 1 s, not 2: the recorder is stopped last, and a recorder behind at load 22 used the whole
#: 2 s, its stop then ending 2.45 s after the launcher's signal (issue 48: within 2 s). What
#: its subscriptions still hold is written as it closes (``RecorderNode.take_pending``).
DRAIN_S = 1.0
#: ``drain_taken`` ends once nothing was taken for this long (s).
DRAIN_QUIET_S = 0.25


def drain_taken(executor: Executor, taken: Callable[[], int], budget_s: float = DRAIN_S,
                quiet_s: float = DRAIN_QUIET_S) -> None:
    """Spin while ``taken()`` grows: until ``quiet_s`` without, or ``budget_s`` in all.

    After a stop the executor no longer spins, so messages that had reached the process but
    not the node's callbacks (a recorder behind on a busy machine: the controller's one task
    record among them) would be lost; some are still in the middleware's hands (a reliable
    writer's repeats), hence the quiet time rather than one empty turn.
    """
    last = time.monotonic()
    end = last + budget_s
    count = taken()
    while True:
        executor.spin_once(timeout_sec=0.01)
        now = time.monotonic()
        if taken() != count:
            count, last = taken(), now
        if now - last >= quiet_s or now >= end:
            return


def schedule_process(node: Node) -> None:
    """Apply the node's ``rt_priority``, ``rt_cpus`` and ``rt_lock_memory`` to its process.

    The one place a node process (or a composed one, with its first node) asks for real-time
    scheduling (``uvms_common.scheduling``), after the node is built (imports, kernels and
    allocations done) and before it spins: ``-p rt_priority:=50`` as ``uvms launch`` passes
    it to the loop processes. A refusal is one warning line; the node runs on.

    Raises:
        ValueError: A value out of range (a start-up error of the node).
    """
    from rcl_interfaces.msg import ParameterDescriptor, ParameterType

    declared = {
        'rt_priority': (0, ParameterDescriptor(
            type=ParameterType.PARAMETER_INTEGER,
            description='SCHED_FIFO priority of the process, 1-99; 0: normal scheduling')),
        'rt_cpus': ('', ParameterDescriptor(
            dynamic_typing=True,
            description="CPUs to pin the process to ('0,1', 1 or [0, 1]); '': every CPU")),
        'rt_lock_memory': (False, ParameterDescriptor(
            type=ParameterType.PARAMETER_BOOL,
            description='lock the pages of the process in RAM (mlockall)')),
    }
    values = {}
    for name, (default, descriptor) in declared.items():
        if not node.has_parameter(name):
            node.declare_parameter(name, default, descriptor)
        values[name] = node.get_parameter(name).value
    request = Scheduling(int(values['rt_priority']), parse_cpus(values['rt_cpus']),
                         bool(values['rt_lock_memory']))
    if not request.asks:
        return
    outcome = apply_scheduling(request)
    if outcome.refused:
        node.get_logger().warning(outcome.refused)
    if outcome.applied:
        node.get_logger().info('real-time scheduling: ' + ', '.join(outcome.applied))


#: rclpy's middleware teardown: what ``middleware_teardown_skipped`` makes a no-op.
_TEARDOWN_METHODS = (
    ('rclpy.node', 'Node', ('destroy_node', 'destroy_publisher', 'destroy_subscription',
                            'destroy_client', 'destroy_service', 'destroy_timer',
                            'destroy_guard_condition', 'destroy_rate')),
    ('rclpy.action.client', 'ActionClient', ('destroy',)),
    ('rclpy.action.server', 'ActionServer', ('destroy',)),
)


@contextlib.contextmanager
def middleware_teardown_skipped() -> Iterator[None]:
    """Within the block rclpy's entity and node destruction does nothing.

    For a process about to end: a node's ``destroy_node`` override then does its own work
    (cancel a goal, put a device back) and its ``super().destroy_node()`` returns at once.
    Bound methods taken before the block (``own(self.destroy_timer, ...)``) still destroy.
    Only modules already imported are patched: a process without an action server has none
    to skip, and importing ``rclpy.action`` at its stop cost it time on a loaded machine.
    """
    saved: list[tuple[type, str, object]] = []
    for module_name, class_name, methods in _TEARDOWN_METHODS:
        module = sys.modules.get(module_name)
        if module is None:
            continue
        cls = getattr(module, class_name)
        for method in methods:
            saved.append((cls, method, cls.__dict__[method]))
            setattr(cls, method, lambda self, *args, **kwargs: True)
    try:
        yield
    finally:
        for cls, method, original in saved:
            setattr(cls, method, original)


def wait_for_acks(node: Node, budget_s: float = ACK_WAIT_S) -> bool:
    """Wait, ``budget_s`` at most in all, for the node's reliable publishers' acknowledgements.

    Returns:
        Whether every publisher's data was acknowledged in time (best-effort ones at once).
    """
    from rclpy.duration import Duration

    end = time.monotonic() + budget_s
    acked = True
    for publisher in list(node.publishers):
        left_s = max(0.0, end - time.monotonic())
        try:
            acked = publisher.wait_for_all_acked(Duration(seconds=left_s)) and acked
        except Exception:  # a publisher already gone: nothing to wait for
            continue
    return acked


class TeardownDeadline:
    """Ends the process if the teardown outlives its grace period; ``cancel`` when it is done.

    A thread of its own waits the grace period, then writes one line and every thread's
    stack to stderr, flushes Python's and C's stdio and calls ``os._exit(status)``. Only arm
    it once nothing is left to lose (files closed): the process ends without cleanup.
    faulthandler's watchdog (a C thread, no GIL needed) backs it up ``TEARDOWN_BACKSTOP_S``
    later, exiting with status 1, for a teardown that blocks while holding the GIL.
    """

    def __init__(self, logger_name: str, status: int, grace_s: float = TEARDOWN_GRACE_S,
                 backstop_s: float = TEARDOWN_BACKSTOP_S) -> None:
        self._logger_name = logger_name
        self._status = status
        self._grace_s = grace_s
        self._done = threading.Event()
        self._stream = sys.__stderr__ or sys.stderr
        self._thread = threading.Thread(target=self._watch, name='teardown deadline',
                                        daemon=True)
        # Started first: on a loaded machine starting the thread alone took more than the
        # backstop's 2 s once (issue 48: faulthandler then ended a thruster_allocator that
        # was stopping normally, status 1); the backstop counts from the thread's start.
        self._thread.start()
        faulthandler.dump_traceback_later(grace_s + backstop_s, exit=True, file=self._stream)

    def cancel(self) -> None:
        """The teardown finished: nothing is ended."""
        self._done.set()
        faulthandler.cancel_dump_traceback_later()

    def _watch(self) -> None:
        if self._done.wait(self._grace_s):
            return
        # Written directly, not through rclpy's logger: the stuck teardown may hold the
        # logging mutex that rclpy takes around node creation and destruction.
        self._stream.write(
            f'[WARN] [{time.time():.9f}] [{self._logger_name}]: teardown still running '
            f'{self._grace_s:g} s after the output was closed (stuck in the middleware): '
            f'ending the process with status {self._status}; stacks follow\n')
        faulthandler.dump_traceback(file=self._stream, all_threads=True)
        flush_output()
        os._exit(self._status)


def run_node(
    make_node: Callable[[], N],
    args: Sequence[str] | None,
    logger_name: str,
    startup_errors: tuple[type[Exception], ...] = (),
    finished: Callable[[N], bool] | None = None,
    close_output: Callable[[N], None] | None = None,
    taken: Callable[[N], int] | None = None,
    executor_kind: str | None = None,
) -> int:
    """Build a node and spin it until SIGINT/SIGTERM; return the process exit status.

    Args:
        make_node: Builds the node (after ``rclpy.init``).
        args: Command-line arguments for rclpy (``--ros-args ...``); None: ``sys.argv``.
        logger_name: Logger for errors that stop the node.
        startup_errors: Exceptions of a node that cannot start (invalid parameter, ...):
            logged as fatal in one line, exit status 1, no traceback.
        finished: The node's own end (e.g. the simulator reached its duration); exit 0.
        close_output: Closes what the node must not lose (the recorder's file), run first
            in the teardown; after it, a teardown stuck in the middleware ends the process
            (``TeardownDeadline``).
        taken: A count of what the node took (the recorder's messages): after a clean stop
            the executor spins on while it grows (``drain_taken``), before ``close_output``.
        executor_kind: ``events`` or ``single`` (``make_executor``); None: ``UVMS_EXECUTOR``
            or ``events``.

    Returns:
        0 after ``finished``, a signal or an external shutdown, each ending in a clean
        shutdown (as Jazzy's demo nodes exit 0 on Ctrl-C); 1 after a start-up error or an
        error raised by a callback (logged with its type).

    A ``StopEvent`` already installed (``uvms_common.node_entry``, before the node's
    imports) is taken over, so a signal received during the imports counts too; one received
    while the node is being built ends a node process at once (``end_unbuilt``, status 0),
    unless the build has begun to change what a stop must put back (``defer_stop_end``: a
    bridge's activate, the recorder's file), when it ends as soon as it is built.
    """
    ros_environment_defaults()
    earlier = active_stop_event()
    stop = earlier if earlier is not None else StopEvent()
    rclpy.init(args=None if args is None else list(args),
               signal_handler_options=SignalHandlerOptions.NO)
    logger = rclpy.logging.get_logger(logger_name)
    node: N | None = None
    executor: Executor | None = None
    status = 0
    try:
        # Not interrupted by an exception: one raised into the model's or Numba's loading
        # (LLVM callbacks) leaves tracebacks. A stop ends a node process at once (issue 48:
        # under load a build took 4-26 s to end) until the build defers it (defer_stop_end).
        ends = process_ends_after_main()
        building = stop.ending(end_unbuilt) if ends else contextlib.nullcontext()
        # A node that fails to build ends the process: its entities go with it.
        keeping = kept_on_failure() if ends else contextlib.nullcontext()
        with building, keeping:
            node = make_node()
        schedule_process(node)
        executor = make_executor(executor_kind)
        executor.add_node(node)
        built = node
        with profiled(logger_name):
            spin_until_stopped(executor, stop, (lambda: finished(built))
                               if finished is not None else lambda: False)
    except startup_errors as exc:
        logger.fatal(str(exc))
        status = 1
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except Exception as exc:
        logger.fatal(f'{type(exc).__name__}: {exc}')
        status = 1
    finally:
        process_stats.write(logger_name, process_periods())
        if status == 0 and node is not None and executor is not None and taken is not None:
            counted = node
            drain_taken(executor, lambda: taken(counted))
        if node is not None and close_output is not None:
            try:
                close_output(node)
            except Exception as exc:
                logger.fatal(f'closing the output: {type(exc).__name__}: {exc}')
                status = 1
        # Seen in CI and here under load: destroy_node stuck after the work was done, the
        # process SIGKILLed by the launcher. Nothing is left to lose now.
        deadline = TeardownDeadline(logger_name, status)
        if node is not None and process_ends_after_main():
            # The node's own end runs; the middleware's is left to the process's end.
            with middleware_teardown_skipped():
                node.destroy_node()
            wait_for_acks(node)
        else:
            if executor is not None:
                # Off the executor first, which unhooks the node's entities from it: a
                # request or message arriving between the executor's shutdown and the node's
                # destruction otherwise reaches a shut-down EventsExecutor from a DDS thread
                # (a SIGSEGV seen once in CI: the controller, the mission cancelling its goal
                # as the graph stopped; ros2/rclpy#1644 is of this family).
                if node is not None and node in executor.get_nodes():
                    executor.remove_node(node)
                executor.shutdown()
            if node is not None:
                node.destroy_node()
            rclpy.try_shutdown()
        deadline.cancel()
        if stop is not earlier:
            stop.restore()
    return status
