"""Controller re-run: feed a recording's inputs to a fresh controller, compare its outputs.

`uvms replay --rerun-controller` builds a fresh controller node with the run's parameters
(the recording's 'uvms' metadata, then `--params-file`s), feeds it the recorded inputs
(/clock, joint states, odometry, wrench) in log-time order through one executor in this
process, and compares its commands and states with the recorded ones, stamp by stamp.
"""

from __future__ import annotations

import functools
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import rclpy
import yaml
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from uvms_common.node_construction import destroyed_if_construction_fails

from uvms_recording.errors import ReplayError
from uvms_recording.mcap_reader import McapRecording
from uvms_recording.recorded_topics import message_class
from uvms_recording.typestore import uvms_typestore

GENERALIZED_FORCE = 'uvms_msgs/msg/GeneralizedForce'
CONTROLLER_STATE = 'uvms_msgs/msg/ControllerState'


class ReplayStopped(Exception):  # noqa: N818 (a request, not an error)
    """A stop was requested (SIGINT/SIGTERM) while re-running the controller."""


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

    @destroyed_if_construction_fails
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


def _mission_node(recording: McapRecording, namespace: str, context: Context) -> Node | None:
    """The recorded run's ContactTask goals, sent to the re-run controller as in the run.

    The goals' start times are on the recorded /clock, so the re-run controller takes them at
    the same steps. Goals a user sent from outside the run are not in the recording.
    """
    text = (recording.run_metadata or {}).get('mission', '')
    if not text.strip():
        return None
    from uvms_tasks.errors import TaskFileError
    from uvms_tasks.mission_node import MissionNode
    from uvms_tasks.task_file import parse_task_document

    try:
        tasks = parse_task_document(yaml.safe_load(text), f'{recording.path} (mission)')
    except (TaskFileError, yaml.YAMLError) as error:
        msg = f'the recorded mission cannot be read: {error}'
        raise ReplayError(msg) from error
    return MissionNode(tasks, namespace=namespace, context=context,
                       parameter_overrides=[Parameter('use_sim_time', value=True)])


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
            mission = _mission_node(recording, namespace, context)
            if mission is not None:
                nodes.append(mission)
                report.parameter_sources.append(
                    f"recorded mission ('uvms' metadata) of {recording.path.name}")
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
