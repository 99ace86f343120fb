"""Recorder node: subscribes raw to every topic of the graph and writes them to an MCAP file."""

from __future__ import annotations

import atexit
import functools
import sys
import threading
import time
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from rcl_interfaces.msg import (
    FloatingPointRange,
    IntegerRange,
    ParameterDescriptor,
)
from rclpy.clock import Clock, ClockType
from rclpy.exceptions import ParameterException
from rclpy.node import Node
from uvms_common.diagnostics import OK, WARN, DiagnosticsPublisher, RateMeter, Report
from uvms_common.node_construction import destroyed_if_construction_fails
from uvms_common.node_main import run_node
from uvms_common.raw_clock import take_clock_raw
from uvms_common.stop_event import defer_stop_end

from uvms_recording.batched_take import TakenInBatches, log_times_on_clock, take_raw
from uvms_recording.errors import RecordingError
from uvms_recording.mcap_writer import DEFAULT_CHUNK_SIZE, McapRecorder, run_metadata
from uvms_recording.recorded_topics import (
    DEFAULT_TOPICS,
    SUBSCRIPTION_DEPTH,
    message_class,
    parse_topic_spec,
    publisher_qos,
    subscription_qos,
)

COMPRESSIONS = ('zstd', 'lz4', 'none')
#: Default period of the batches (s): 25 messages of a 500 Hz topic, a fortieth of its queue.
DEFAULT_TAKE_PERIOD_S = 0.05


class RecorderNode(Node):
    """Records every graph topic, raw, into the MCAP file of parameter `output_path`.

    Log times are the node clock's time at each message's arrival (ns): simulated time under
    use_sim_time (lockstep, from 0), the Unix epoch otherwise. `close()` (also run by
    `destroy_node()`) writes the file's summary; until then the file is readable up to its
    last complete chunk.

    The subscriptions are taken in batches every ``take_period_s`` by the node itself where
    the executor honours callback groups (the recorder's own process spins a
    SingleThreadedExecutor), and one message at a time by their callbacks where it does not
    (the EventsExecutor): ``uvms_recording.batched_take``.
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
        take_period_s = self.declare_parameter(
            'take_period_s', DEFAULT_TAKE_PERIOD_S,
            ParameterDescriptor(
                description="Period of taking every subscription's waiting messages in one "
                f'batch (s, steady clock); each subscription holds {SUBSCRIPTION_DEPTH}, so '
                'keep it under that many periods of the fastest topic',
                read_only=True,
                floating_point_range=[FloatingPointRange(from_value=0.001, to_value=1.0,
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
        self._take_lock = threading.Lock()  # one batch at a time: the executor's or close()'s
        batches = TakenInBatches()
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
                    callback_group=batches,
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
        self._full_batches = 0
        self.create_timer(take_period_s, self.take_batch,
                          clock=Clock(clock_type=ClockType.STEADY_TIME))
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
        self._write(topic, data, source.last_ns if source.ros_time_is_active
                    else time.time_ns())

    def _write(self, topic: str, data: bytes, log_time_ns: int) -> None:
        self._write_all(topic, ((data, log_time_ns),))

    def _write_all(self, topic: str, messages: Iterable[tuple[bytes, int]]) -> None:
        """Write ``(cdr bytes, log time ns)`` of one topic; count them dropped once closed."""
        with self._lock:
            write = self._recorder.write
            for data, log_time_ns in messages:
                if self._recorder.closed:
                    self._dropped += 1
                    continue
                try:
                    write(topic, data, log_time_ns)
                except RecordingError as error:
                    self._dropped += 1
                    self.get_logger().error(str(error), throttle_duration_sec=5.0)

    def _report(self) -> Report:
        """/diagnostics: file, messages written and their rate, dropped (WARN while dropping)."""
        now_ns = self.get_clock().now().nanoseconds
        written = self._recorder.message_count
        values = {'file': str(self._recorder.path), 'messages_written': written,
                  'write_rate_hz': self._meters[0].rate_hz(written, now_ns),
                  'dropped': self._dropped, 'full_queues': self._full_batches}
        if self._meters[1].rate_hz(self._dropped, now_ns):
            return Report(WARN, 'dropping messages', values)
        if self._full_batches:
            return Report(WARN, 'a subscription queue was full: messages may be lost', values)
        return Report(OK, 'closed' if self._recorder.closed else 'recording', values)

    def taken(self) -> int:
        """Messages taken so far, written or dropped (what a stop drains: ``run_node``)."""
        return self._recorder.message_count + self._dropped

    def take_batch(self) -> int:
        """Write what every subscription holds, /clock first; return how many.

        Each message is logged at the node clock's time of its arrival: its reception time
        on the wall clock, the last /clock stamp received before it under use_sim_time
        (``batched_take.log_times_on_clock``). At most each subscription's depth.
        """
        with self._take_lock:
            source = self._clock_source
            on_sim_time = source.ros_time_is_active
            before_ns = source.last_ns
            clock_received: list[int] = []
            clock_stamps: list[int] = []
            clock = self._subscriptions_by_topic.get('/clock')
            clocks = [] if clock is None else self._take('/clock', clock)
            for data, received_ns in clocks:
                source.raw_clock_callback(data)
                clock_received.append(received_ns)
                clock_stamps.append(source.last_ns)
            self._write_all('/clock', zip((data for data, _ in clocks),
                                          clock_stamps if on_sim_time else clock_received,
                                          strict=True))
            taken = len(clocks)
            for topic, subscription in self._subscriptions_by_topic.items():
                if subscription is clock:
                    continue
                batch = self._take(topic, subscription)
                received = [received_ns for _, received_ns in batch]
                if not on_sim_time:
                    log_times = received
                elif clock is not None:
                    log_times = log_times_on_clock(received, clock_received, clock_stamps,
                                                   before_ns)
                else:  # the time source's own /clock subscription sets the clock
                    log_times = [source.last_ns] * len(batch)
                self._write_all(topic, zip((data for data, _ in batch), log_times,
                                           strict=True))
                taken += len(batch)
            return taken

    def _take(self, topic: str, subscription: Any) -> list[tuple[bytes, int]]:
        """One subscription's waiting messages; a full queue is warned about (it may drop)."""
        if self._recorder.closed:
            return []
        batch = take_raw(subscription, SUBSCRIPTION_DEPTH)
        if len(batch) == SUBSCRIPTION_DEPTH:
            self._full_batches += 1
            self.get_logger().warning(
                f'{topic}: {SUBSCRIPTION_DEPTH} messages in one batch, its whole queue: '
                'messages may have been lost; lower take_period_s',
                throttle_duration_sec=5.0)
        return batch

    def take_pending(self) -> int:
        """Write what the middleware still holds for the subscriptions; return how many.

        A recorder behind on a busy machine has messages in its subscriptions' queues that
        it has not taken yet: measured, the controller's one task record among them when
        the stop's drain ended (``run_node``). One batch (``take_batch``).
        """
        return self.take_batch()

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

    Spun by a SingleThreadedExecutor, which leaves the subscriptions to the node's batches
    (``take_batch``). What had arrived before the stop is taken first (up to 1 s). The file
    is closed before the middleware teardown, whose hang then costs nothing: the process ends
    itself after a grace period (``uvms_common.node_main.run_node``).
    """
    sys.exit(run_node(RecorderNode, args, 'recorder', (RecordingError, ParameterException),
                      close_output=RecorderNode.close, taken=RecorderNode.taken,
                      executor_kind='single'))

if __name__ == '__main__':
    main()
