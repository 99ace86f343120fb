"""Crash-tolerant MCAP writer of ROS 2 recordings (ros2 profile, rosbag2_storage_mcap layout).

The files are what Jazzy's rosbag2_storage_mcap writes and reads: profile 'ros2', one schema
per message type (name 'pkg/msg/Type', encoding 'ros2msg', the full concatenated definition),
one channel per topic (message encoding 'cdr', metadata 'offered_qos_profiles' and
'topic_type_hash'), zstd or lz4 compressed chunks with message indexes, and a summary with a
Statistics record. The `mcap` library writes the container; rosbags provides the schemas.

Timestamps are integer nanoseconds since the epoch of the ROS clock that recorded them: the
simulated clock in lockstep runs (the simulation starts at 0), the Unix epoch in real-time
runs. Nothing here imports rclpy.
"""

from __future__ import annotations

import io
import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from types import TracebackType
from typing import Any, Literal

import yaml
from mcap.well_known import MessageEncoding, Profile, SchemaEncoding
from mcap.writer import LIBRARY_IDENTIFIER, CompressionType, Writer

from uvms_recording.errors import RecordingError
from uvms_recording.typestore import (
    InterfaceError,
    message_definition,
    normalize_type_name,
    type_hash,
)

#: Name of the MCAP metadata record holding the run's parameters (see `run_metadata`).
RUN_METADATA_NAME = 'uvms'
#: Chunk size after which a chunk is compressed and written (bytes, uncompressed).
DEFAULT_CHUNK_SIZE = 1024 * 1024
#: Longest span of log time a chunk may cover before it is written (ns): bounds what a crash
#: loses when messages arrive slowly.
DEFAULT_FLUSH_INTERVAL_NS = 1_000_000_000

#: rmw's RMW_DURATION_INFINITE, as rosbag2 writes it into offered_qos_profiles.
_INFINITE_DURATION = {'sec': 9223372036, 'nsec': 854775807}

Compression = Literal['zstd', 'lz4', 'none']
_COMPRESSION_TYPES = {
    'zstd': CompressionType.ZSTD,
    'lz4': CompressionType.LZ4,
    'none': CompressionType.NONE,
}


def _library_identifier() -> str:
    try:
        own = version('uvms-stack')
    except PackageNotFoundError:
        own = 'source'
    return f'uvms_recording/{own}; {LIBRARY_IDENTIFIER}'


@dataclass(frozen=True)
class QosDescription:
    """QoS a publisher offers, stored per topic in 'offered_qos_profiles' for `ros2 bag play`.

    Policy values are the rmw names rosbag2 (metadata version 9, Jazzy) writes: reliability
    'reliable' | 'best_effort', durability 'volatile' | 'transient_local', history
    'keep_last' | 'keep_all'. Deadline, lifespan and liveliness lease are infinite.
    """

    reliability: str = 'reliable'
    durability: str = 'volatile'
    history: str = 'keep_last'
    depth: int = 10

    def as_rosbag2_dict(self) -> dict[str, Any]:
        """The profile as the mapping rosbag2 serializes, keys in rosbag2's order."""
        return {
            'history': self.history,
            'depth': self.depth,
            'reliability': self.reliability,
            'durability': self.durability,
            'deadline': dict(_INFINITE_DURATION),
            'lifespan': dict(_INFINITE_DURATION),
            'liveliness': 'automatic',
            'liveliness_lease_duration': dict(_INFINITE_DURATION),
            'avoid_ros_namespace_conventions': False,
        }


def offered_qos_profiles_yaml(profiles: Iterable[QosDescription]) -> str:
    """YAML text of a list of QoS profiles, laid out as rosbag2 (yaml-cpp) writes it."""
    dumped = yaml.safe_dump(
        [profile.as_rosbag2_dict() for profile in profiles],
        sort_keys=False,
        default_flow_style=False,
    )
    return dumped.rstrip('\n')


def run_metadata(
    scenario: str,
    seed: int,
    parameters_yaml: str,
    **extra: str,
) -> dict[str, str]:
    """Contents of the 'uvms' metadata record, from which replay rebuilds the controller.

    Args:
        scenario: Scenario name (e.g. 'case1_ke1e4').
        seed: Random seed of the run.
        parameters_yaml: ROS 2 parameter file text of the run (node name -> ros__parameters).
        **extra: Further string entries (e.g. mode='lockstep').

    """
    return {'scenario': scenario, 'seed': str(seed), 'parameters': parameters_yaml, **extra}


class _UnbufferedSink:
    """File sink without a user-space buffer, so every record the writer emits reaches the OS.

    The mcap writer only emits whole records (a finished chunk with its indexes, a metadata
    record), so a process that dies leaves a file that ends after its last complete chunk
    (plus, at worst, part of one record).
    """

    def __init__(self, path: Path) -> None:
        self._file = io.FileIO(path, 'w')
        self._position = 0

    def write(self, data: bytes | bytearray | memoryview) -> int:
        view = memoryview(data)
        while view:
            written = self._file.write(view)
            if written is None:  # pragma: no cover - only for non-blocking files
                continue
            view = view[written:]
        self._position += len(data)
        return len(data)

    def tell(self) -> int:
        return self._position

    def flush(self) -> None:
        """Nothing to flush: writes go straight to the OS."""

    def close(self) -> None:
        try:
            os.fsync(self._file.fileno())
        finally:
            self._file.close()


class McapRecorder:
    """Writes serialized ROS 2 messages (CDR) to an MCAP file as rosbag2_storage_mcap does.

    Use as a context manager, or call `close()`: closing writes the summary (schemas,
    channels, Statistics, chunk indexes) that `ros2 bag` needs. A file whose writer never
    closed (crash, SIGKILL) is still readable up to its last complete chunk with
    `open_recording`; a chunk is written when it holds `chunk_size` bytes or spans
    `flush_interval_ns` of log time, whichever comes first.

    Timestamps are integer nanoseconds since the epoch of the recording's ROS clock:
    simulated time (starting at 0) in lockstep runs, the Unix epoch in real time.

    Example:
        >>> with McapRecorder('run.mcap') as recorder:  # doctest: +SKIP
        ...     recorder.add_topic('/uvms/joint_states', 'sensor_msgs/msg/JointState')
        ...     recorder.write('/uvms/joint_states', cdr_bytes, log_time_ns=1_000_000)

    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        *,
        compression: Compression = 'zstd',
        chunk_size: int = DEFAULT_CHUNK_SIZE,
        flush_interval_ns: int | None = DEFAULT_FLUSH_INTERVAL_NS,
        metadata: Mapping[str, str] | None = None,
    ) -> None:
        """Create the file (replacing an existing one) and write the MCAP header.

        Args:
            path: Output file, conventionally '*.mcap'.
            compression: Chunk compression: 'zstd' (default), 'lz4' or 'none'.
            chunk_size: Uncompressed bytes after which a chunk is written (> 0).
            flush_interval_ns: Log-time span after which a chunk is written even if not full
                (ns, > 0), or None for size only.
            metadata: Entries of the 'uvms' metadata record (see `run_metadata`), written
                at once so that even a cut-short file keeps them.

        Raises:
            RecordingError: Invalid option, or the file cannot be created.

        """
        self.path = Path(path)
        if compression not in _COMPRESSION_TYPES:
            msg = (
                f'cannot record {self.path}: compression {compression!r} is not one of '
                f'{sorted(_COMPRESSION_TYPES)}'
            )
            raise RecordingError(msg)
        if chunk_size <= 0:
            msg = f'cannot record {self.path}: chunk_size {chunk_size} must be > 0 bytes'
            raise RecordingError(msg)
        if flush_interval_ns is not None and flush_interval_ns <= 0:
            msg = (
                f'cannot record {self.path}: flush_interval_ns {flush_interval_ns} must be '
                '> 0 or None'
            )
            raise RecordingError(msg)
        try:
            self._sink = _UnbufferedSink(self.path)
        except OSError as error:
            msg = f'cannot create recording {self.path}: {error.strerror}'
            raise RecordingError(msg) from None
        self._writer = Writer(
            self._sink,  # type: ignore[arg-type]
            chunk_size=chunk_size,
            compression=_COMPRESSION_TYPES[compression],
        )
        self._writer.start(profile=Profile.ROS2, library=_library_identifier())
        self._schema_ids: dict[str, int] = {}
        self._channel_ids: dict[str, int] = {}
        self._sequences: dict[str, int] = {}
        self._flush_interval_ns = flush_interval_ns
        self._chunk_start_ns: int | None = None
        self._closed = False
        self.message_count = 0
        if metadata is not None:
            self._add_metadata(RUN_METADATA_NAME, metadata)

    def __enter__(self) -> McapRecorder:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()

    @property
    def closed(self) -> bool:
        """Whether `close()` has run."""
        return self._closed

    @property
    def topics(self) -> tuple[str, ...]:
        """Topics added so far, in order."""
        return tuple(self._channel_ids)

    def _check_open(self, action: str) -> None:
        if self._closed:
            msg = f'cannot {action}: recording {self.path} is already closed'
            raise RecordingError(msg)

    def _add_metadata(self, name: str, entries: Mapping[str, str]) -> None:
        bad = {key: type(value).__name__ for key, value in entries.items()
               if not isinstance(key, str) or not isinstance(value, str)}
        if bad:
            msg = (
                f'cannot write metadata {name!r} to {self.path}: keys and values must be '
                f'strings, got {bad}'
            )
            raise RecordingError(msg)
        self._writer.add_metadata(name, dict(entries))

    def add_topic(self, topic: str, type_name: str, qos: QosDescription | None = None) -> None:
        """Register a topic: its schema (once per type) and its channel.

        Args:
            topic: Fully qualified topic name (e.g. '/uvms/joint_states').
            type_name: Message type 'pkg/msg/Type' (a Jazzy type or one of uvms_msgs).
            qos: QoS the topic's publishers offer (default: reliable, volatile, keep last 10).

        Raises:
            RecordingError: Topic already added, unknown type, or recording closed.

        """
        self._check_open(f'add topic {topic!r}')
        if topic in self._channel_ids:
            msg = f'cannot add topic {topic!r} to {self.path}: it was already added'
            raise RecordingError(msg)
        try:
            name = normalize_type_name(type_name)
            definition = message_definition(name)
            rihs01 = type_hash(name)
        except InterfaceError as error:
            msg = f'cannot add topic {topic!r} to {self.path}: {error}'
            raise RecordingError(msg) from None
        schema_id = self._schema_ids.get(name)
        if schema_id is None:
            schema_id = self._writer.register_schema(
                name=name, encoding=SchemaEncoding.ROS2, data=definition.encode()
            )
            self._schema_ids[name] = schema_id
        self._channel_ids[topic] = self._writer.register_channel(
            topic=topic,
            message_encoding=MessageEncoding.CDR,
            schema_id=schema_id,
            metadata={
                'offered_qos_profiles': offered_qos_profiles_yaml([qos or QosDescription()]),
                'topic_type_hash': rihs01,
            },
        )
        self._sequences[topic] = 0

    def write(
        self,
        topic: str,
        data: bytes,
        log_time_ns: int,
        publish_time_ns: int | None = None,
    ) -> None:
        """Append one serialized message.

        Args:
            topic: A topic registered with `add_topic`.
            data: The message serialized as CDR (e.g. a raw subscription's bytes).
            log_time_ns: Time the recorder received it (ns since the recording clock's epoch).
            publish_time_ns: Time it was published (ns, same epoch); defaults to log_time_ns.

        Raises:
            RecordingError: Unknown topic, negative time, or recording closed.

        """
        channel_id = self._channel_ids.get(topic)
        if channel_id is None:
            self._check_open(f'write to {topic!r}')
            msg = (
                f'cannot write to {topic!r} in {self.path}: add_topic() was not called for it '
                f'(topics: {list(self._channel_ids)})'
            )
            raise RecordingError(msg)
        if self._closed:  # checked here, not by _check_open: this runs once per message
            self._check_open(f'write to {topic!r}')
        if log_time_ns < 0:
            msg = f'cannot write to {topic!r} in {self.path}: log time {log_time_ns} ns < 0'
            raise RecordingError(msg)
        sequence = self._sequences[topic] + 1
        self._sequences[topic] = sequence
        self._writer.add_message(
            channel_id,
            log_time_ns,
            data if type(data) is bytes else bytes(data),
            log_time_ns if publish_time_ns is None else publish_time_ns,
            sequence,
        )
        self.message_count += 1
        if self._flush_interval_ns is not None:
            if self._chunk_start_ns is None:
                self._chunk_start_ns = log_time_ns
            elif log_time_ns - self._chunk_start_ns >= self._flush_interval_ns:
                self.flush()

    def flush(self) -> None:
        """Write the chunk in progress now (a crash then loses nothing written so far)."""
        self._check_open('flush')
        self._writer.flush()
        self._chunk_start_ns = None

    def close(self) -> None:
        """Write the last chunk, the summary with its Statistics record, and close the file.

        Idempotent. No 'rosbag2' metadata record is written: ros2 bag reads everything it
        needs from the summary.
        """
        if self._closed:
            return
        self._closed = True
        try:
            self._writer.finish()
        finally:
            self._sink.close()


__all__ = [
    'DEFAULT_CHUNK_SIZE',
    'DEFAULT_FLUSH_INTERVAL_NS',
    'RUN_METADATA_NAME',
    'McapRecorder',
    'QosDescription',
    'offered_qos_profiles_yaml',
    'run_metadata',
]
