"""Recorder node: subscribes raw to every topic of the graph and writes them to an MCAP file."""

from __future__ import annotations

import atexit
import functools
import importlib
import sys
import threading
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from rcl_interfaces.msg import (
    FloatingPointRange,
    IntegerRange,
    ParameterDescriptor,
)
from rclpy.exceptions import ParameterException
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from uvms_common.diagnostics import OK, WARN, DiagnosticsPublisher, RateMeter, Report
from uvms_common.node_construction import destroyed_if_construction_fails
from uvms_common.node_main import run_node
from uvms_common.raw_clock import take_clock_raw
from uvms_common.stop_event import defer_stop_end

from uvms_recording.errors import RecordingError
from uvms_recording.mcap_writer import (
    DEFAULT_CHUNK_SIZE,
    McapRecorder,
    QosDescription,
    run_metadata,
)
from uvms_recording.typestore import InterfaceError, normalize_type_name

#: The graph's topics as 'name:type' (DESIGN.md); relative names resolve in the node's
#: namespace (/uvms by default), /clock, /tf and /tf_static are absolute.
DEFAULT_TOPICS = (
    '/clock:rosgraph_msgs/msg/Clock',
    'joint_states:sensor_msgs/msg/JointState',
    'odometry:nav_msgs/msg/Odometry',
    'wrench:geometry_msgs/msg/WrenchStamped',
    'ee_pose:geometry_msgs/msg/PoseStamped',
    'contact:uvms_msgs/msg/ContactState',
    'command/generalized_force:uvms_msgs/msg/GeneralizedForce',
    'controller/state:uvms_msgs/msg/ControllerState',
    'controller/task_record:uvms_msgs/msg/ContactTaskRecord',
    'controller/mode:std_msgs/msg/String',
    'command/actuators:uvms_msgs/msg/ActuatorCommand',
    'thrusters/state:uvms_msgs/msg/ThrusterState',
    'thrusters/health:uvms_msgs/msg/ThrusterHealth',
    '/tf:tf2_msgs/msg/TFMessage',
    '/tf_static:tf2_msgs/msg/TFMessage',
    '/robot_description:std_msgs/msg/String',
    'markers:visualization_msgs/msg/MarkerArray',
    'ocean/current:geometry_msgs/msg/TwistStamped',
)

COMPRESSIONS = ('zstd', 'lz4', 'none')
#: Depth of the recorder's subscriptions: lockstep publishes in bursts faster than real time.
SUBSCRIPTION_DEPTH = 1000


def parse_topic_spec(spec: str) -> tuple[str, str]:
    """Split a 'topic:pkg/msg/Type' entry of the `topics` parameter.

    Raises:
        RecordingError: The entry is not 'topic:type' with a valid type name.

    """
    topic, separator, type_name = spec.rpartition(':')
    if not separator or not topic or not type_name:
        msg = f"parameter 'topics': entry {spec!r} is not 'topic:pkg/msg/Type'"
        raise RecordingError(msg)
    try:
        return topic, normalize_type_name(type_name)
    except InterfaceError as error:
        msg = f"parameter 'topics': entry {spec!r}: {error}"
        raise RecordingError(msg) from None


def message_class(type_name: str) -> type[Any]:
    """The Python message class of 'pkg/msg/Type', imported from its message package.

    Raises:
        RecordingError: The package or the type cannot be imported.

    """
    package, _, name = normalize_type_name(type_name).split('/')
    try:
        module = importlib.import_module(f'{package}.msg')
        return getattr(module, name)  # type: ignore[no-any-return]
    except (ImportError, AttributeError):
        msg = f'message type {type_name!r} cannot be imported (is package {package!r} built?)'
        raise RecordingError(msg) from None


def publisher_qos(topic: str) -> QosDescription:
    """QoS the graph's publishers offer on a topic, as tf2_ros and our nodes publish.

    /tf_static and /robot_description are latched (reliable, transient local, depth 1, as
    tf2_ros and robot_state_publisher offer them), /tf reliable with depth 100; every other
    graph publisher is reliable, volatile, keep last 10 (rclpy's default).
    """
    if topic.endswith(('/tf_static', '/robot_description')):
        return QosDescription(durability='transient_local', depth=1)
    if topic.endswith('/tf'):
        return QosDescription(depth=100)
    return QosDescription()


def subscription_qos(topic: str) -> QoSProfile:
    """QoS of the recorder's subscription, compatible with the publisher and deep enough.

    /clock is subscribed best effort as rclpy's own time source does, which matches a
    reliable or a best-effort /clock publisher alike.
    """
    offered = publisher_qos(topic)
    if offered.durability == 'transient_local':
        return QoSProfile(
            history=HistoryPolicy.KEEP_LAST,
            depth=offered.depth,
            reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.TRANSIENT_LOCAL,
        )
    reliability = (ReliabilityPolicy.BEST_EFFORT if topic == '/clock'
                   else ReliabilityPolicy.RELIABLE)
    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST,
        depth=SUBSCRIPTION_DEPTH,
        reliability=reliability,
        durability=DurabilityPolicy.VOLATILE,
    )


class RecorderNode(Node):
    """Records every graph topic, raw, into the MCAP file of parameter `output_path`.

    Log times are the node clock's now (ns): simulated time under use_sim_time (lockstep,
    from 0), the Unix epoch otherwise. `close()` (also run by `destroy_node()`) writes the
    file's summary; until then the file is readable up to its last complete chunk.
    """

    @destroyed_if_construction_fails
    def __init__(self, **kwargs: Any) -> None:
        """Declare parameters, open the MCAP file and subscribe.

        Args:
            **kwargs: Passed to rclpy's Node (e.g. namespace, context, parameter_overrides).

        Raises:
            RecordingError: Invalid parameter (named, with its value and valid values), or
                the file cannot be created.

        """
        super().__init__('recorder', **kwargs)
        self._clock_source = take_clock_raw(self)  # /clock raw under use_sim_time
        output_path = self.declare_parameter(
            'output_path', '',
            ParameterDescriptor(description='MCAP file to write (required), e.g. run.mcap',
                                read_only=True),
        ).value
        topic_specs = self.declare_parameter(
            'topics', list(DEFAULT_TOPICS),
            ParameterDescriptor(description="Topics to record, each 'topic:pkg/msg/Type'; "
                                'relative names resolve in the node namespace',
                                read_only=True),
        ).value
        compression = self.declare_parameter(
            'compression', 'zstd',
            ParameterDescriptor(description='Chunk compression: zstd, lz4 or none',
                                read_only=True),
        ).value
        chunk_size = self.declare_parameter(
            'chunk_size_bytes', DEFAULT_CHUNK_SIZE,
            ParameterDescriptor(
                description='Uncompressed size after which a chunk is written (bytes)',
                read_only=True,
                integer_range=[IntegerRange(from_value=1024, to_value=1 << 30, step=1)],
            ),
        ).value
        flush_interval_s = self.declare_parameter(
            'flush_interval_s', 1.0,
            ParameterDescriptor(
                description='Clock time after which a chunk is written even if not full (s); '
                'bounds what a crash loses',
                read_only=True,
                floating_point_range=[FloatingPointRange(from_value=0.001, to_value=3600.0,
                                                         step=0.0)],
            ),
        ).value
        scenario = self.declare_parameter(
            'run.scenario', '',
            ParameterDescriptor(description="Scenario name stored in the 'uvms' metadata",
                                read_only=True),
        ).value
        seed = self.declare_parameter(
            'run.seed', 0,
            ParameterDescriptor(description="Random seed stored in the 'uvms' metadata",
                                read_only=True),
        ).value
        parameters_yaml = self.declare_parameter(
            'run.parameters', '',
            ParameterDescriptor(description="ROS 2 parameter YAML of the run, stored in the "
                                "'uvms' metadata so that replay can rebuild the controller",
                                read_only=True),
        ).value
        mission = self.declare_parameter(
            'run.mission', '',
            ParameterDescriptor(description="Mission file text of the run's ContactTask goals, "
                                "stored in the 'uvms' metadata so that replay can send them to "
                                'the re-run controller', read_only=True),
        ).value
        mode = self.declare_parameter(
            'run.mode', '',
            ParameterDescriptor(description="Execution mode stored in the 'uvms' metadata "
                                '(lockstep or realtime)', read_only=True),
        ).value

        if not output_path:
            msg = "parameter 'output_path' is required: the MCAP file to write (got '')"
            raise RecordingError(msg)
        if compression not in COMPRESSIONS:
            msg = (f"parameter 'compression' is {compression!r}; valid values: "
                   f'{", ".join(COMPRESSIONS)}')
            raise RecordingError(msg)
        topics = [parse_topic_spec(spec) for spec in topic_specs]
        classes = {type_name: message_class(type_name) for _, type_name in topics}

        metadata = None
        if scenario or parameters_yaml or mode:
            metadata = run_metadata(scenario, seed, parameters_yaml)
            if mode:
                metadata['mode'] = mode
            if mission:
                metadata['mission'] = mission
        path = Path(output_path)
        path.parent.mkdir(parents=True, exist_ok=True)
        defer_stop_end()  # a stop until here ends the build at once; from here the file is closed
        self._recorder = McapRecorder(
            path,
            compression=compression,
            chunk_size=chunk_size,
            flush_interval_ns=round(flush_interval_s * 1e9),
            metadata=metadata,
        )
        self._subscriptions_by_topic: dict[str, Any] = {}
        self._lock = threading.Lock()
        # Closed at exit whatever happens: a stop signal that interrupts the node's start-up
        # after this point (run_node) leaves no node to close, yet the file gets its summary.
        atexit.register(self._close_at_exit)
        try:
            for topic, type_name in topics:
                resolved = self.resolve_topic_name(topic)
                if resolved in self._subscriptions_by_topic:
                    continue
                self._recorder.add_topic(resolved, type_name, publisher_qos(resolved))
                self._subscriptions_by_topic[resolved] = self.create_subscription(
                    classes[type_name],
                    resolved,
                    self._on_clock if resolved == '/clock'
                    else functools.partial(self._on_message, resolved),
                    subscription_qos(resolved),
                    raw=True,
                )
            if '/clock' in self._subscriptions_by_topic:
                # The recording's own /clock subscription sets the node clock: the time
                # source keeps none of its own (500 messages a second fewer).
                self._clock_source.feed_from_node()
        except BaseException:
            self._recorder.close()
            raise
        self._dropped = 0
        self._meters = (RateMeter(), RateMeter())  # messages written, dropped
        self._diagnostics = DiagnosticsPublisher(self)
        self._diagnostics.add('recording', self._report)
        self.get_logger().info(
            f'recording {len(self._subscriptions_by_topic)} topics to {path} '
            f'({compression}, log time = node clock)'
        )

    @property
    def recorder(self) -> McapRecorder:
        """The MCAP writer (for its path and message count)."""
        return self._recorder

    def _on_clock(self, data: bytes) -> None:
        """/clock: set the node clock (under use_sim_time), then record the message."""
        self._clock_source.raw_clock_callback(data)
        self._on_message('/clock', data)

    def _on_message(self, topic: str, data: bytes) -> None:
        # The node clock's now, without building rclpy Time objects per message: the last
        # /clock stamp under use_sim_time (what ROSClock.now() returns then), else the
        # system clock.
        source = self._clock_source
        log_time_ns = source.last_ns if source.ros_time_is_active else time.time_ns()
        with self._lock:
            if self._recorder.closed:
                self._dropped += 1
                return
            try:
                self._recorder.write(topic, data, log_time_ns)
            except RecordingError as error:
                self._dropped += 1
                self.get_logger().error(str(error), throttle_duration_sec=5.0)

    def _report(self) -> Report:
        """/diagnostics: file, messages written and their rate, dropped (WARN while dropping)."""
        now_ns = self.get_clock().now().nanoseconds
        written = self._recorder.message_count
        values = {'file': str(self._recorder.path), 'messages_written': written,
                  'write_rate_hz': self._meters[0].rate_hz(written, now_ns),
                  'dropped': self._dropped}
        if self._meters[1].rate_hz(self._dropped, now_ns):
            return Report(WARN, 'dropping messages', values)
        return Report(OK, 'closed' if self._recorder.closed else 'recording', values)

    def taken(self) -> int:
        """Messages taken so far, written or dropped (what a stop drains: ``run_node``)."""
        return self._recorder.message_count + self._dropped

    def take_pending(self) -> int:
        """Write what the middleware still holds for the subscriptions; return how many.

        A recorder behind on a busy machine has messages in its subscriptions' queues that
        its executor has not taken yet: measured, the controller's one task record among
        them when the stop's drain ended (``run_node``). Taken here straight from each
        subscription, /clock first so that the others' log times are its latest; at most
        each subscription's depth.
        """
        taken = 0
        for topic, subscription in self._subscriptions_by_topic.items():
            write = self._on_clock if topic == '/clock' else functools.partial(
                self._on_message, topic)
            while not self._recorder.closed:
                with subscription.handle:
                    message = subscription.handle.take_message(subscription.msg_type, True)
                if message is None:
                    break
                write(message[0])
                taken += 1
        return taken

    def close(self) -> None:
        """Take what is still pending, write the file's summary and close it (idempotent).

        Later messages are dropped. Safe to call from another thread than the executor's.
        """
        if not self._recorder.closed:
            pending = self.take_pending()
            if pending:
                self.get_logger().info(f'took {pending} pending messages before closing')
        with self._lock:
            if self._recorder.closed:
                return
            self._recorder.close()
        self.get_logger().info(
            f'closed {self._recorder.path}: {self._recorder.message_count} messages'
        )

    def _close_at_exit(self) -> None:
        """Close the file if nothing did (no logging: rclpy may be shut down by then)."""
        with self._lock:
            if not self._recorder.closed:
                self._recorder.close()

    def destroy_node(self) -> None:
        """Close the recording, then destroy the node."""
        self.close()
        super().destroy_node()


def main(args: Sequence[str] | None = None) -> None:
    """Run the recorder until SIGINT or SIGTERM, then close the MCAP file cleanly.

    What had arrived before the stop is taken first (up to 1 s). The file is closed before
    the middleware teardown, whose hang then costs nothing: the process ends itself after a
    grace period (``uvms_common.node_main.run_node``).
    """
    sys.exit(run_node(RecorderNode, args, 'recorder', (RecordingError, ParameterException),
                      close_output=RecorderNode.close, taken=RecorderNode.taken))

if __name__ == '__main__':
    main()
