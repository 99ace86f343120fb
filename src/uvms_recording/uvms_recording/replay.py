"""`uvms replay`: publish a recording back onto its topics, or re-run the controller on it.

Plain replay publishes each recorded message (raw CDR bytes) on its topic with the recorded
spacing of log times divided by `--rate`, on the replay's own monotonic wall clock (not the
ROS clock: replay is what drives time). `/clock` is replayed only with `--clock`.

`--rerun-controller` hands the recording to `uvms_recording.rerun`, which re-runs the
controller on the recorded inputs and compares its outputs with the recorded ones.
"""

from __future__ import annotations

import argparse
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import FrameType
from typing import Any

import numpy as np
import rclpy
from rclpy.context import Context
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from uvms_common.node_construction import destroyed_if_construction_fails

from uvms_recording.errors import RecordingError, ReplayError
from uvms_recording.mcap_reader import McapRecording, RecordedMessage, open_recording
from uvms_recording.mcap_writer import QosDescription
from uvms_recording.recorded_topics import message_class
from uvms_recording.rerun import ReplayStopped, rerun_controller

#: Longest single wait between two checks that the replay should go on (s).
_WAIT_SLICE_S = 0.1


@dataclass(frozen=True)
class ReplayOptions:
    """How to replay: rate factor, topic filter, looping, start offset, /clock."""

    rate: float = 1.0
    topics: tuple[str, ...] = ()
    loop: bool = False
    start_s: float = 0.0
    clock: bool = False


def select_topics(recording: McapRecording, options: ReplayOptions) -> list[str]:
    """Recorded topics to publish: the requested ones (default all), /clock only with --clock.

    Raises:
        ReplayError: A requested topic is not in the recording.

    """
    recorded = list(recording.topics)
    if options.topics:
        missing = [topic for topic in options.topics if topic not in recording.topics]
        if missing:
            msg = (f'{recording.path} has no topic {", ".join(missing)}; recorded topics: '
                   f'{", ".join(recorded)}')
            raise ReplayError(msg)
        chosen = list(options.topics)
    else:
        chosen = recorded
    if options.clock:
        if '/clock' in recording.topics and '/clock' not in chosen:
            chosen.append('/clock')
    elif not options.topics:
        chosen = [topic for topic in chosen if topic != '/clock']
    return chosen


def play_messages(
    passes: Callable[[], Iterable[RecordedMessage]],
    publish: Callable[[RecordedMessage], None],
    *,
    rate: float = 1.0,
    loop: bool = False,
    now: Callable[[], float] = time.monotonic,
    sleep: Callable[[float], None] = time.sleep,
    keep_going: Callable[[], bool] = lambda: True,
) -> int:
    """Publish recorded messages at their recorded pace, scaled by rate; return how many.

    Message i of a pass is published at wall time t0 + (log_i - log_0) / rate, t0 being the
    wall time (s, from `now`) of the pass's first message. Late messages go out at once.

    Args:
        passes: Returns a fresh iterable of the messages, in log-time order, per pass.
        publish: Publishes one message.
        rate: Speed factor (> 0): 2 plays twice as fast.
        loop: Start over after the last message until keep_going() is False.
        now: Monotonic clock (s).
        sleep: Waits (s); called with slices of at most 0.1 s.
        keep_going: Checked between waits and messages; False stops the replay.

    Raises:
        ReplayError: rate is not a finite number > 0.

    """
    if not (np.isfinite(rate) and rate > 0.0):
        msg = f'replay rate must be a finite number > 0, got {rate}'
        raise ReplayError(msg)
    published = 0
    while True:
        start_wall: float | None = None
        start_log_ns = 0
        in_pass = 0
        for message in passes():
            if start_wall is None:
                start_wall, start_log_ns = now(), message.log_time_ns
            due = start_wall + (message.log_time_ns - start_log_ns) / 1e9 / rate
            while (delay := due - now()) > 0.0:
                if not keep_going():
                    return published
                sleep(min(delay, _WAIT_SLICE_S))
            if not keep_going():
                return published
            publish(message)
            published += 1
            in_pass += 1
        if not loop or in_pass == 0 or not keep_going():
            return published


def _qos_profile(offered: QosDescription) -> QoSProfile:
    """The rclpy QoS of a recorded offered profile (unknown policies fall back to defaults)."""
    return QoSProfile(
        history=(HistoryPolicy.KEEP_ALL if offered.history == 'keep_all'
                 else HistoryPolicy.KEEP_LAST),
        depth=max(offered.depth, 1),
        reliability=(ReliabilityPolicy.BEST_EFFORT if offered.reliability == 'best_effort'
                     else ReliabilityPolicy.RELIABLE),
        durability=(DurabilityPolicy.TRANSIENT_LOCAL if offered.durability == 'transient_local'
                    else DurabilityPolicy.VOLATILE),
    )


class ReplayNode(Node):
    """Publishes a recording's messages, raw, on their recorded topics with recorded QoS."""

    @destroyed_if_construction_fails
    def __init__(self, recording: McapRecording, topics: Iterable[str], **kwargs: Any) -> None:
        """Create one publisher per topic, typed and with the QoS the recording offers.

        Args:
            recording: The opened recording.
            topics: Topics to publish (absolute names, as recorded).
            **kwargs: Passed to rclpy's Node (e.g. context).

        Raises:
            RecordingError: A recorded type cannot be imported.

        """
        super().__init__('replay', **kwargs)
        self.recording = recording
        self._publishers_by_topic: dict[str, Any] = {}
        for topic in topics:
            info = recording.topics[topic]
            offered = info.offered_qos()
            qos = _qos_profile(offered[0] if offered else QosDescription())
            self._publishers_by_topic[topic] = self.create_publisher(
                message_class(info.type_name), topic, qos
            )

    @property
    def topics(self) -> list[str]:
        """Topics this node publishes."""
        return list(self._publishers_by_topic)

    def publish_recorded(self, message: RecordedMessage) -> None:
        """Publish one recorded message's bytes on its topic."""
        self._publishers_by_topic[message.topic].publish(message.data)

    def play(
        self,
        options: ReplayOptions,
        *,
        now: Callable[[], float] = time.monotonic,
        sleep: Callable[[float], None] = time.sleep,
        should_stop: Callable[[], bool] = lambda: False,
        on_published: Callable[[RecordedMessage], None] | None = None,
    ) -> int:
        """Replay the selected topics as options say; return the number of messages published.

        Stops early when the node's context shuts down or should_stop() turns True;
        ``on_published`` is told of each message published (a progress line).
        """
        start_ns = self.recording.start_time_ns + round(options.start_s * 1e9)
        topics = self.topics

        def publish(message: RecordedMessage) -> None:
            self.publish_recorded(message)
            if on_published is not None:
                on_published(message)

        return play_messages(
            lambda: self.recording.messages(topics, start_ns=start_ns),
            publish,
            rate=options.rate,
            loop=options.loop,
            now=now,
            sleep=sleep,
            keep_going=lambda: self.context.ok() and not should_stop(),
        )


class ReplayProgress:
    """``replayed 5.0 / 20.0 s of the recording`` from log times start_ns to end_ns (ns).

    On a terminal one line redrawn every 0.5 s of wall time (``now``, s); else one every 5 s.
    """

    def __init__(self, start_ns: int, end_ns: int, file: Any = None,
                 now: Callable[[], float] = time.monotonic) -> None:
        self.start_ns = start_ns
        self.total_s = max(end_ns - start_ns, 0) * 1e-9
        self.file = sys.stderr if file is None else file
        self.now = now
        self.tty = bool(getattr(self.file, 'isatty', lambda: False)())
        self._next_s = -float('inf')

    def __call__(self, message: RecordedMessage) -> None:
        """Note one published message; write the line when it is due."""
        t = self.now()
        if t < self._next_s:
            return
        self._next_s = t + (0.5 if self.tty else 5.0)
        done = max(message.log_time_ns - self.start_ns, 0) * 1e-9
        text = f'replayed {done:.1f} / {self.total_s:.1f} s of the recording'
        self.file.write(f'\r{text}' if self.tty else f'{text}\n')
        self.file.flush()

    def end(self) -> None:
        """End a redrawn line."""
        if self.tty:
            self.file.write('\n')


class StopOnSignal:
    """While active, SIGINT and SIGTERM request a stop instead of killing the replay.

    The replay then ends between two messages, cleanly. Only the main thread can install
    signal handlers (elsewhere this does nothing); an ignored SIGINT (a background job) stays
    ignored. The previous handlers come back on exit.
    """

    def __init__(self) -> None:
        self.requested = False
        self._previous: dict[int, Any] = {}

    def __enter__(self) -> StopOnSignal:
        if threading.current_thread() is threading.main_thread():
            for signum in (signal.SIGINT, signal.SIGTERM):
                if signal.getsignal(signum) is not signal.SIG_IGN:
                    self._previous[signum] = signal.signal(signum, self._request)
        return self

    def _request(self, signum: int, frame: FrameType | None) -> None:
        self.requested = True

    def __exit__(self, *exc_info: object) -> None:
        for signum, handler in self._previous.items():
            signal.signal(signum, handler if handler is not None else signal.SIG_DFL)
        self._previous.clear()


# Command line ------------------------------------------------------------------------------

def build_parser() -> argparse.ArgumentParser:
    """Argument parser of `uvms replay`."""
    parser = argparse.ArgumentParser(
        prog='uvms replay',
        description='Publish a recording (MCAP) back onto its topics, or re-run the '
        'controller on its inputs and compare with its recorded outputs.',
    )
    parser.add_argument('recording', metavar='F.mcap', type=Path, help='recording to replay')
    parser.add_argument('--rate', type=float, default=1.0,
                        help='speed factor of the replay (default 1: recorded pace)')
    parser.add_argument('--topics', nargs='+', default=[], metavar='T',
                        help='replay only these topics (absolute names, as recorded)')
    parser.add_argument('--loop', action='store_true', help='start over at the end')
    parser.add_argument('--start', type=float, default=0.0, metavar='S',
                        help='skip the first S seconds of the recording')
    parser.add_argument('--clock', action='store_true',
                        help='also publish the recorded /clock')
    parser.add_argument('--rerun-controller', action='store_true',
                        help='re-run the controller on the recorded inputs and report its '
                        'deviation from the recorded outputs')
    parser.add_argument('--params-file', action='append', default=[], type=Path,
                        metavar='P', help='controller parameter file applied after the '
                        'recorded parameters (repeatable; with --rerun-controller)')
    parser.add_argument('--tolerance', type=float, default=1e-6,
                        help='largest accepted deviation per field, in its unit (N, N*m, 1); '
                        'default 1e-6')
    parser.add_argument('--timeout', type=float, default=5.0, metavar='S',
                        help='longest wait for one controller output (s, default 5)')
    return parser


def _split_ros_args(argv: Sequence[str]) -> tuple[list[str], list[str]]:
    argv = list(argv)
    if '--ros-args' in argv:
        index = argv.index('--ros-args')
        return argv[:index], argv[index:]
    return argv, []


def main(argv: Sequence[str] | None = None) -> int:
    """Run `uvms replay`; argv excludes the program name. Returns the exit status.

    0: replayed (also when stopped by SIGINT/SIGTERM) or re-run within tolerance;
    1: recording unreadable, replay failed, or re-run outside tolerance; 2: invalid
    arguments; 130: a re-run interrupted.
    """
    own_args, ros_args = _split_ros_args(sys.argv[1:] if argv is None else argv)
    parser = build_parser()
    try:
        args = parser.parse_args(own_args)
    except SystemExit as exit_:
        return int(exit_.code or 0)

    def fail(message: str, status: int = 1) -> int:
        print(f'uvms replay: error: {message}', file=sys.stderr)
        return status

    if not (np.isfinite(args.rate) and args.rate > 0.0):
        return fail(f'--rate must be a finite number > 0, got {args.rate}', 2)
    if not (np.isfinite(args.tolerance) and args.tolerance >= 0.0):
        return fail(f'--tolerance must be a finite number >= 0, got {args.tolerance}', 2)
    if not (np.isfinite(args.timeout) and args.timeout > 0.0):
        return fail(f'--timeout must be a finite number > 0 s, got {args.timeout}', 2)
    if args.start < 0.0:
        return fail(f'--start must be >= 0 s, got {args.start}', 2)
    if args.rerun_controller and (args.loop or args.topics or args.rate != 1.0):
        return fail('--rerun-controller feeds every input as fast as the controller answers; '
                    'it takes no --rate, --topics or --loop', 2)
    try:
        recording = open_recording(args.recording)
    except RecordingError as error:
        return fail(str(error))
    if recording.problem is not None:
        print(f'uvms replay: warning: {recording.problem}', file=sys.stderr)

    with StopOnSignal() as stop:
        try:
            if args.rerun_controller:
                report = rerun_controller(
                    recording, params_files=args.params_file, tolerance=args.tolerance,
                    timeout_s=args.timeout, should_stop=lambda: stop.requested,
                )
                print(report.render())
                return 0 if report.passed else 1
            return _replay(recording, args, ros_args, lambda: stop.requested)
        except (RecordingError, ReplayError) as error:
            return fail(str(error))
        except (KeyboardInterrupt, ReplayStopped):
            print('uvms replay: interrupted', file=sys.stderr)
            return 130


def _replay(recording: McapRecording, args: argparse.Namespace, ros_args: list[str],
            should_stop: Callable[[], bool]) -> int:
    options = ReplayOptions(rate=args.rate, topics=tuple(args.topics), loop=args.loop,
                            start_s=args.start, clock=args.clock)
    if options.clock and '/clock' not in recording.topics:
        print(f'uvms replay: warning: {recording.path} has no /clock to publish',
              file=sys.stderr)
    topics = select_topics(recording, options)
    context = Context()
    rclpy.init(args=['uvms_replay', *ros_args], context=context)
    node: ReplayNode | None = None
    try:
        node = ReplayNode(recording, topics, context=context)
        print(f'replaying {recording.path} ({len(topics)} topics, rate {options.rate:g}'
              f'{", loop" if options.loop else ""})', file=sys.stderr)
        progress = ReplayProgress(recording.start_time_ns + round(options.start_s * 1e9),
                                  recording.end_time_ns)
        count = node.play(options, should_stop=should_stop, on_published=progress)
        progress.end()
        stopped = ' (stopped)' if should_stop() else ''
        print(f'published {count} messages{stopped}', file=sys.stderr)
        return 0
    except ExternalShutdownException:
        return 0
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown(context=context)


if __name__ == '__main__':
    sys.exit(main())
