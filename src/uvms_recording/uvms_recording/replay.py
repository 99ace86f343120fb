"""`uvms replay`: publish a recording back onto its topics, or re-run the controller on it.

Plain replay publishes each recorded message (raw CDR bytes) on its topic with the recorded
spacing of log times divided by `--rate`, on the replay's own monotonic wall clock (not the
ROS clock: replay is what drives time). `/clock` is replayed only with `--clock`.

`--rerun-controller` builds a fresh controller node with the run's parameters (the
recording's 'uvms' metadata, then `--params-file`s), feeds it the recorded inputs (/clock,
joint states, odometry, wrench) in log-time order through one executor in this process, and
compares its commands and states with the recorded ones, stamp by stamp.
"""

from __future__ import annotations

import argparse
import functools
import signal
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import FrameType
from typing import Any

import numpy as np
import rclpy
from rclpy.context import Context
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from uvms_recording.recorder_node import message_class
from uvms_recording.recording import (
    McapRecording,
    QosDescription,
    RecordedMessage,
    RecordingError,
    ReplayError,
    open_recording,
)
from uvms_recording.typestore import uvms_typestore

#: Longest single wait between two checks that the replay should go on (s).
_WAIT_SLICE_S = 0.1
GENERALIZED_FORCE = 'uvms_msgs/msg/GeneralizedForce'
CONTROLLER_STATE = 'uvms_msgs/msg/ControllerState'


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
    ) -> int:
        """Replay the selected topics as options say; return the number of messages published.

        Stops early when the node's context shuts down or should_stop() turns True.
        """
        start_ns = self.recording.start_time_ns + round(options.start_s * 1e9)
        topics = self.topics
        return play_messages(
            lambda: self.recording.messages(topics, start_ns=start_ns),
            self.publish_recorded,
            rate=options.rate,
            loop=options.loop,
            now=now,
            sleep=sleep,
            keep_going=lambda: self.context.ok() and not should_stop(),
        )


class ReplayStopped(Exception):  # noqa: N818 (a request, not an error)
    """A stop was requested (SIGINT/SIGTERM) while re-running the controller."""


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


# Re-running the controller -----------------------------------------------------------------

@dataclass
class Deviation:
    """Largest absolute difference of one output field between re-run and recording."""

    field: str
    unit: str
    max_abs: float = 0.0
    at_time_ns: int | None = None

    def update(self, difference: float, t_ns: int) -> None:
        """Keep the larger of the current and the new difference (NaN counts as infinite)."""
        value = float('inf') if np.isnan(difference) else abs(difference)
        if self.at_time_ns is None or value > self.max_abs:
            self.max_abs, self.at_time_ns = value, t_ns


def _vector(message: Any, name: str) -> np.ndarray:
    value = message
    for part in name.split('.'):
        value = getattr(value, part)
    return np.array([value.x, value.y, value.z], dtype=float)


#: Compared fields per output type: (field label, unit, extractor).
OUTPUT_FIELDS: dict[str, list[tuple[str, str, Callable[[Any], np.ndarray]]]] = {
    GENERALIZED_FORCE: [
        ('vehicle force', 'N', lambda m: _vector(m, 'vehicle_wrench.force')),
        ('vehicle moment', 'N*m', lambda m: _vector(m, 'vehicle_wrench.torque')),
        ('joint torques', 'N*m', lambda m: np.asarray(m.joint_torques, dtype=float)),
    ],
    CONTROLLER_STATE: [
        ('weight W', '1', lambda m: np.array([m.weight], dtype=float)),
        ('command force F_c', 'N', lambda m: _vector(m, 'command_force')),
    ],
}


def output_differences(type_name: str, recorded: bytes, rerun: bytes) -> dict[str, float]:
    """Largest absolute difference per compared field of two CDR messages of one output type.

    A field whose arrays differ in length differs by infinity.
    """
    store = uvms_typestore()
    old = store.deserialize_cdr(recorded, type_name)
    new = store.deserialize_cdr(rerun, type_name)
    differences: dict[str, float] = {}
    for label, _, extract in OUTPUT_FIELDS[type_name]:
        a, b = extract(old), extract(new)
        if a.shape != b.shape:
            differences[label] = float('inf')
        elif a.size == 0:
            differences[label] = 0.0
        else:
            delta = np.abs(a - b)
            differences[label] = float('inf') if np.isnan(delta).any() else float(delta.max())
    return differences


def header_stamp_ns(type_name: str, data: bytes) -> int:
    """Header stamp (ns) of a CDR message with a std_msgs/Header 'header'."""
    message: Any = uvms_typestore().deserialize_cdr(data, type_name)
    stamp = message.header.stamp
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


@dataclass
class RerunReport:
    """Outcome of a controller re-run: per-field deviations, missing outputs, verdict."""

    recording: Path
    tolerance: float
    compared: int = 0
    missing: list[tuple[str, int]] = field(default_factory=list)
    deviations: dict[str, Deviation] = field(default_factory=dict)
    parameter_sources: list[str] = field(default_factory=list)

    @property
    def passed(self) -> bool:
        """Every recorded output was reproduced within tolerance."""
        return (self.compared > 0 and not self.missing
                and all(d.max_abs <= self.tolerance for d in self.deviations.values()))

    def render(self) -> str:
        """The report as text: one line per field, then the verdict."""
        lines = [
            f'controller re-run on {self.recording}: {self.compared} recorded outputs compared',
            'parameters: ' + (', '.join(self.parameter_sources) or 'node defaults'),
            f'{"field":<20} {"unit":<5} {"max |deviation|":>16}  at t [s]',
        ]
        for deviation in self.deviations.values():
            at = ('-' if deviation.at_time_ns is None or deviation.max_abs == 0.0
                  else f'{deviation.at_time_ns / 1e9:.6f}')
            flag = '  > tolerance' if deviation.max_abs > self.tolerance else ''
            lines.append(f'{deviation.field:<20} {deviation.unit:<5} '
                         f'{deviation.max_abs:>16.6g}  {at}{flag}')
        if self.missing:
            first_topic, first_t = self.missing[0]
            lines.append(f'missing outputs: {len(self.missing)} (first: {first_topic} at '
                         f't = {first_t / 1e9:.6f} s)')
        verdict = 'PASS' if self.passed else 'FAIL'
        lines.append(f"{verdict}: tolerance {self.tolerance:g} (in each field's unit)")
        return '\n'.join(lines)


def controller_namespace(recording: McapRecording) -> str:
    """Namespace of the recorded controller, from its command topic ('/uvms' by default).

    Raises:
        ReplayError: The recording has no generalized force command to compare with.

    """
    for topic, info in recording.topics.items():
        if info.type_name == GENERALIZED_FORCE and topic.endswith('/command/generalized_force'):
            return topic[: -len('/command/generalized_force')] or '/'
    msg = (f'{recording.path} has no command/generalized_force topic: there is no recorded '
           'controller output to compare a re-run with')
    raise ReplayError(msg)


class _RerunFeeder(Node):
    """Publishes recorded controller inputs raw and collects the controller's outputs raw."""

    def __init__(self, recording: McapRecording, inputs: Sequence[str],
                 outputs: Sequence[str], **kwargs: Any) -> None:
        super().__init__('replay_rerun_feeder', **kwargs)
        deep = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000,
                          reliability=ReliabilityPolicy.RELIABLE,
                          durability=DurabilityPolicy.VOLATILE)
        self.input_publishers = {
            topic: self.create_publisher(message_class(recording.topics[topic].type_name),
                                         topic, deep)
            for topic in inputs
        }
        self.received: dict[tuple[str, int], bytes] = {}
        self.output_subscriptions = []
        for topic in outputs:
            type_name = recording.topics[topic].type_name
            self.output_subscriptions.append(self.create_subscription(
                message_class(type_name), topic,
                lambda data, t=topic, n=type_name: self._on_output(t, n, data),
                deep, raw=True,
            ))

    def _on_output(self, topic: str, type_name: str, data: bytes) -> None:
        self.received[(topic, header_stamp_ns(type_name, data))] = bytes(data)


def _params_file_from_metadata(recording: McapRecording, directory: Path) -> Path | None:
    metadata = recording.run_metadata or {}
    text = metadata.get('parameters', '')
    if not text.strip():
        return None
    path = directory / 'recorded_parameters.yaml'
    path.write_text(text, encoding='utf-8')
    return path


def _spin_until(executor: SingleThreadedExecutor, done: Callable[[], bool],
                timeout_s: float) -> bool:
    deadline = time.monotonic() + timeout_s
    while not done():
        remaining = deadline - time.monotonic()
        if remaining <= 0.0:
            return False
        executor.spin_once(timeout_sec=min(remaining, 0.05))
    return True


def _make_controller(context: Context) -> Node:
    try:
        from uvms_control.controller_node import ControllerNode
    except ImportError as error:
        msg = f'cannot re-run the controller: uvms_control.controller_node is missing ({error})'
        raise ReplayError(msg) from None
    try:
        return ControllerNode(context=context)  # type: ignore[no-any-return]
    except TypeError as error:
        msg = ('cannot re-run the controller: ControllerNode must accept rclpy Node keyword '
               f'arguments (context=...): {error}')
        raise ReplayError(msg) from None


def rerun_controller(
    recording: McapRecording,
    *,
    params_files: Sequence[Path] = (),
    tolerance: float = 1e-6,
    timeout_s: float = 5.0,
    should_stop: Callable[[], bool] = lambda: False,
) -> RerunReport:
    """Re-run the controller on the recorded inputs and compare with the recorded outputs.

    Args:
        recording: A recording of the lockstep graph (the controller answers each set of
            inputs with one command stamped like them).
        params_files: ROS 2 parameter files applied after the recorded parameters.
        tolerance: Largest accepted deviation per field, in the field's unit.
        timeout_s: Longest wall time to wait for one output.
        should_stop: Polled while feeding; True raises ReplayStopped.

    Raises:
        ReplayError: No controller outputs recorded, controller node unavailable, or the
            controller never answers (e.g. a real-time recording).
        ReplayStopped: should_stop() turned True.

    """
    namespace = controller_namespace(recording)
    mode = (recording.run_metadata or {}).get('mode', '')
    if mode and mode != 'lockstep':
        msg = (f'{recording.path} was recorded in {mode!r} mode; re-running the controller '
               'needs a lockstep recording (one controller output per set of inputs)')
        raise ReplayError(msg)
    prefix = '' if namespace == '/' else namespace
    inputs = [topic for topic in ('/clock', f'{prefix}/joint_states', f'{prefix}/odometry',
                                  f'{prefix}/wrench') if topic in recording.topics]
    outputs = [topic for topic in (f'{prefix}/command/generalized_force',
                                   f'{prefix}/controller/state') if topic in recording.topics]
    report = RerunReport(recording=recording.path, tolerance=tolerance)
    for topic in outputs:
        for label, unit, _ in OUTPUT_FIELDS[recording.topics[topic].type_name]:
            report.deviations[label] = Deviation(label, unit)

    with tempfile.TemporaryDirectory(prefix='uvms_rerun_') as tmp:
        ros_args = ['--ros-args', '-r', f'__ns:={namespace}']
        recorded_params = _params_file_from_metadata(recording, Path(tmp))
        for path in [p for p in (recorded_params,) if p is not None] + list(params_files):
            ros_args += ['--params-file', str(path)]
        if recorded_params is not None:
            report.parameter_sources.append(f"recorded 'uvms' metadata of {recording.path.name}")
        report.parameter_sources += [str(path) for path in params_files]

        context = Context()
        rclpy.init(args=['uvms_replay', *ros_args], context=context)
        executor = SingleThreadedExecutor(context=context)
        nodes: list[Node] = []
        try:
            controller = _make_controller(context)
            nodes.append(controller)
            feeder = _RerunFeeder(recording, inputs, outputs, context=context)
            nodes.append(feeder)
            for node in nodes:
                executor.add_node(node)
            _feed_and_compare(recording, feeder, executor, inputs, outputs, report, timeout_s,
                              should_stop)
        finally:
            for node in nodes:
                executor.remove_node(node)
                node.destroy_node()
            executor.shutdown()
            rclpy.try_shutdown(context=context)
    return report


def _feed_and_compare(
    recording: McapRecording,
    feeder: _RerunFeeder,
    executor: SingleThreadedExecutor,
    inputs: Sequence[str],
    outputs: Sequence[str],
    report: RerunReport,
    timeout_s: float,
    should_stop: Callable[[], bool],
) -> None:
    """Publish inputs in log order; at each recorded output, wait for the re-run's and compare."""
    connected = _spin_until(
        executor,
        lambda: (all(p.get_subscription_count() > 0 for p in feeder.input_publishers.values())
                 and all(feeder.count_publishers(t) > 0 for t in outputs)),
        timeout_s,
    )
    if not connected:
        msg = ('cannot re-run the controller: it did not connect to '
               f'{", ".join(inputs)} / {", ".join(outputs)} within {timeout_s} s')
        raise ReplayError(msg)
    type_names = {topic: recording.topics[topic].type_name for topic in outputs}
    for message in recording.messages([*inputs, *outputs]):
        if should_stop():
            raise ReplayStopped
        if message.topic in feeder.input_publishers:
            feeder.input_publishers[message.topic].publish(message.data)
            continue
        stamp_ns = header_stamp_ns(message.type_name, message.data)
        key = (message.topic, stamp_ns)
        if not _spin_until(executor, functools.partial(feeder.received.__contains__, key),
                           timeout_s):
            report.missing.append(key)
            if report.compared == 0:
                msg = (f'the re-run controller published no {message.topic} for the inputs '
                       f'stamped t = {stamp_ns / 1e9:.6f} s within {timeout_s} s; re-running '
                       'needs a lockstep recording (the controller answers each input set)')
                raise ReplayError(msg)
            continue
        rerun = feeder.received.pop(key)
        for label, value in output_differences(type_names[message.topic], message.data,
                                               rerun).items():
            report.deviations[label].update(value, message.log_time_ns)
        report.compared += 1


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
        count = node.play(options, should_stop=should_stop)
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
