"""``uvms task FILE.yaml``: send a task or mission file to a running graph and follow it.

Joins the graph of the ROS domain in the environment, sends each task through the
controller's ContactTask action (the next when the previous one SUCCEEDED), shows a progress
line on stderr (state, phase, W, force, progress) and prints each result on stdout. A task
whose first waypoint is away from the controller's X_d starts with a transit there: a line
on stderr says how far and how long. A goal the controller rejects is printed ``REJECTED:``
with the reason the controller logged (read back from /rosout). Ctrl-C cancels the running
goal (the controller ramps the force down and backs off) and exits 130.

Exit status: 0 every task SUCCEEDED, 1 one did not (or no controller answered), 2 a bad file
or bad usage, 130 interrupted.

In a process that ends as soon as ``main`` returns (``python -m uvms_tasks.cli``, or a caller
that said so with ``uvms_common.node_entry.mark_process_ends_after_main``), the node and the
action client are not destroyed: once the results are printed the process's end frees them,
so a teardown stuck in DDS (issue 48: a stack in rclpy's ``ActionClient.destroy``) cannot
keep ``uvms task`` from exiting with its status. Called in a process that goes on (a test, a
script), ``main`` tears down as any rclpy program does.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, TextIO

from uvms_common.node_entry import end_process, mark_process_ends_after_main
from uvms_common.node_entry import process_ends_after_main as _process_ends_after_main
from uvms_common.ros_environment import ros_environment_defaults
from uvms_common.stop_event import StopEvent, active_stop_event

from uvms_tasks.errors import TaskClientError, TaskFileError
from uvms_tasks.goals import TaskOutcome, describe_feedback, describe_task
from uvms_tasks.task_file import TaskSpec, load_task_file

if TYPE_CHECKING:
    from uvms_tasks.client import ContactTaskClient

EXIT_OK = 0
EXIT_FAILURE = 1
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130
#: Wall seconds to wait for the result of a canceled goal (the controller retreats first).
CANCEL_WAIT_S = 10.0
#: Shortest interval between two progress line updates (s).
PROGRESS_INTERVAL_S = 0.1


def build_parser() -> argparse.ArgumentParser:
    """Argument parser of ``uvms task``."""
    parser = argparse.ArgumentParser(
        prog='uvms task',
        description='Send a task or mission file (uvms_tasks.task_file) to the controller of '
                    'a running graph through its ContactTask action, show the feedback and '
                    'print each result. Ctrl-C cancels the running goal.')
    parser.add_argument('file', metavar='FILE.yaml', help='task or mission file')
    parser.add_argument('--namespace', default='/uvms', metavar='NS',
                        help="the graph's namespace (default /uvms: "
                             '/uvms/controller/contact_task)')
    parser.add_argument('--timeout', type=float, default=10.0, metavar='S',
                        help='seconds to wait for the action server, the controller state and '
                             'the answer to each goal (default 10)')
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``uvms task``; returns the exit status."""
    try:
        args = build_parser().parse_args(list(sys.argv[1:] if argv is None else argv))
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else EXIT_USAGE
    if not args.timeout > 0.0:
        _error(f'--timeout: expected seconds > 0, got {args.timeout}')
        return EXIT_USAGE
    try:
        tasks = load_task_file(args.file)
    except TaskFileError as exc:
        _error(str(exc))
        return EXIT_USAGE
    ros_environment_defaults()
    installed = active_stop_event()
    stop = installed if installed is not None else StopEvent()
    try:
        return _send_tasks(tasks, args.namespace, args.timeout, stop)
    finally:
        if stop is not installed:
            stop.restore()


def _error(message: str) -> None:
    """One-line error on stderr."""
    print(f'uvms task: error: {message}', file=sys.stderr)


def _send_tasks(tasks: list[TaskSpec], namespace: str, timeout_s: float,
                stop: StopEvent) -> int:
    """Join the graph, send the tasks in order, report; the exit status."""
    import rclpy
    from rclpy.node import Node
    from rclpy.signals import SignalHandlerOptions

    from uvms_tasks.client import ContactTaskClient

    rclpy.init(args=[], signal_handler_options=SignalHandlerOptions.NO)
    node = Node(f'uvms_task_{os.getpid()}', namespace=namespace)
    client = ContactTaskClient(node)
    run = _TaskRun(client, stop, timeout_s)
    try:
        return run.run(tasks)
    except TaskClientError as exc:
        run.progress.end()
        _error(str(exc))
        return EXIT_FAILURE
    finally:
        sys.stdout.flush()
        if not _process_ends_after_main():
            client.destroy()
            node.destroy_node()
            rclpy.try_shutdown()


class _TaskRun:
    """The tasks of one ``uvms task`` call, sent and followed on the client's executor."""

    def __init__(self, client: ContactTaskClient, stop: StopEvent, timeout_s: float) -> None:
        self.client = client
        self.stop = stop
        self.timeout_s = timeout_s
        self.progress = _ProgressLine(sys.stderr)

    def spin(self, done: Callable[[], bool], timeout_s: float | None) -> bool:
        """Spin until done() (True), a stop signal or the timeout (False)."""
        self.client.spin_until(lambda: done() or self.stop.is_set(), timeout_s)
        return done()

    def run(self, tasks: list[TaskSpec]) -> int:
        """Send every task, stopping after the first that does not succeed."""
        client = self.client
        client.watch_rejections()
        if not self.spin(client.server_is_ready, self.timeout_s):
            if self.stop.is_set():
                return EXIT_INTERRUPTED
            msg = f'no action server {client.action_name} within {self.timeout_s:g} s'
            raise TaskClientError(msg)
        # The server must discover this new client too before it can answer (client.py).
        from uvms_tasks.client import DISCOVERY_SETTLE_S

        self.spin(lambda: False, DISCOVERY_SETTLE_S)
        if self.stop.is_set():
            return EXIT_INTERRUPTED
        if any(task.needs_start for task in tasks) and not self.spin(
                lambda: client.latest_state is not None, self.timeout_s):
            if self.stop.is_set():
                return EXIT_INTERRUPTED
            msg = f'no controller/state message within {self.timeout_s:g} s (X0 of half circle)'
            raise TaskClientError(msg)
        for i, task in enumerate(tasks):
            outcome = self.run_task(task)
            if outcome is None:
                return EXIT_INTERRUPTED
            self.progress.end()
            print(outcome.describe(), flush=True)
            if not outcome.succeeded:
                skipped = len(tasks) - i - 1
                if skipped:
                    print(f'not sent: {skipped} remaining task(s)', file=sys.stderr)
                return EXIT_FAILURE
        return EXIT_OK

    def run_task(self, task: TaskSpec) -> TaskOutcome | None:
        """Send one task and wait for its end; None when interrupted (the goal canceled)."""
        from uvms_tasks.goals import goal_from_task

        client = self.client
        state = client.latest_state
        start = None if state is None else (state.desired_position.x,
                                             state.desired_position.y,
                                             state.desired_position.z)
        print(f'sending {describe_task(task)}', file=sys.stderr, flush=True)
        goal = goal_from_task(task, start)
        transit = _TransitNote(task.name, goal, start, self.progress)
        since = time.monotonic()
        sent = client.send_goal_async(goal, transit.feedback)
        if not self.spin(sent.done, self.timeout_s):
            # Interrupted before the answer: wait for it, so that an accepted goal is canceled.
            if not self.stop.is_set() or not client.spin_until(sent.done, self.timeout_s):
                msg = f'{client.action_name}: no answer to {task.name} in {self.timeout_s:g} s'
                raise TaskClientError(msg)
        handle = sent.result()
        if not handle.accepted:
            return TaskOutcome(task.name, int(handle.status), rejected=True,
                               reason=client.rejection_reason(since))
        result = client.result_async(handle)
        if not self.spin(result.done, None):
            self.cancel(task, handle, result)
            return None
        self.progress.end()
        response = result.result()
        return TaskOutcome(task.name, int(response.status), response.result)

    def cancel(self, task: TaskSpec, handle: Any, result: Any) -> None:
        """Cancel an interrupted goal and print its result if it comes in time."""
        self.progress.end()
        print(f'uvms task: interrupted: canceling {task.name}', file=sys.stderr, flush=True)
        self.client.cancel_async(handle)
        done = self.client.spin_until(result.done, CANCEL_WAIT_S)
        # The feedback of the retreat redrew the progress line while waiting: leave it, or
        # the result (stdout, the same terminal) is glued onto it.
        self.progress.end()
        if done:
            response = result.result()
            print(TaskOutcome(task.name, int(response.status), response.result).describe(),
                  flush=True)


class _TransitNote:
    """Says once, on stderr, that a goal starts with a transit to its first waypoint."""

    def __init__(self, name: str, goal: Any, start: Sequence[float] | None,
                 progress: _ProgressLine) -> None:
        self.name = name
        self.first = (goal.path[0].x, goal.path[0].y, goal.path[0].z) if goal.path else None
        self.start = start
        self.progress = progress
        self.said = False

    def feedback(self, feedback: Any) -> None:
        """Pass the feedback on to the progress line, after the note at the first transit."""
        if not self.said and feedback.transit_s > 0.0:
            self.said = True
            self.progress.end()
            distance = ('' if self.start is None or self.first is None
                        else f' {math.dist(self.start, self.first):.3f} m')
            print(f'{self.name}: transit{distance} from X_d to path[0] first, in '
                  f'{feedback.transit_s:.2f} s (the path times count from its end)',
                  file=sys.stderr, flush=True)
        self.progress.update(feedback)


class _ProgressLine:
    """The feedback as one line rewritten in place (a terminal only; nothing otherwise)."""

    def __init__(self, stream: TextIO) -> None:
        self.stream = stream
        self.enabled = stream.isatty()
        self._shown = False
        self._last = 0.0

    def update(self, feedback: Any) -> None:
        """Show the latest feedback, at most every PROGRESS_INTERVAL_S."""
        now = time.monotonic()
        if not self.enabled or now - self._last < PROGRESS_INTERVAL_S:
            return
        self._last = now
        self.stream.write(f'\r\x1b[K{describe_feedback(feedback)}')
        self.stream.flush()
        self._shown = True

    def end(self) -> None:
        """Leave the line (before a result or an error is printed)."""
        if self._shown:
            self.stream.write('\n')
            self.stream.flush()
            self._shown = False


def console_main() -> None:
    """``python -m uvms_tasks.cli``: run ``main``, then end the process without DDS teardown."""
    mark_process_ends_after_main()
    end_process(main())


if __name__ == '__main__':
    console_main()
