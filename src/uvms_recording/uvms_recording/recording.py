"""MCAP recordings with the ros2 profile: a crash-tolerant writer and a truncation-tolerant reader.

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
import struct
import warnings
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from types import TracebackType
from typing import Any, BinaryIO, Literal, NamedTuple

import yaml
import zstandard
from mcap.exceptions import EndOfFile, McapError
from mcap.reader import SeekingReader
from mcap.records import Channel, Chunk, Footer, Message, Metadata, Schema, Statistics
from mcap.stream_reader import StreamReader, breakup_chunk
from mcap.well_known import MessageEncoding, Profile, SchemaEncoding
from mcap.writer import LIBRARY_IDENTIFIER, CompressionType, Writer

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

MCAP_MAGIC = b'\x89MCAP0\r\n'
#: rmw's RMW_DURATION_INFINITE, as rosbag2 writes it into offered_qos_profiles.
_INFINITE_DURATION = {'sec': 9223372036, 'nsec': 854775807}

Compression = Literal['zstd', 'lz4', 'none']
_COMPRESSION_TYPES = {
    'zstd': CompressionType.ZSTD,
    'lz4': CompressionType.LZ4,
    'none': CompressionType.NONE,
}

# What reading a cut or damaged MCAP can raise inside the mcap library and the decompressors.
_DAMAGED_DATA_ERRORS = (
    McapError,
    struct.error,
    ValueError,
    RuntimeError,
    EOFError,
    KeyError,
    IndexError,
    zstandard.ZstdError,
    MemoryError,
)


class RecordingError(Exception):
    """A recording cannot be written or read (names the file and what is wrong)."""


class ReplayError(Exception):
    """A recording cannot be replayed or its controller re-run as asked."""


class RecordingTruncatedWarning(UserWarning):
    """A recording was cut short (e.g. the recorder crashed): only its complete chunks are read."""


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


class RecordedMessage(NamedTuple):
    """One recorded message: topic, type 'pkg/msg/Type', log time (ns) and CDR bytes."""

    topic: str
    type_name: str
    log_time_ns: int
    data: bytes


@dataclass(frozen=True)
class RecordedTopic:
    """A topic of a recording, from its MCAP channel and schema."""

    topic: str
    type_name: str
    message_count: int
    offered_qos_profiles: str = ''
    type_hash: str = ''
    definition: str = ''

    def offered_qos(self) -> list[QosDescription]:
        """The offered QoS profiles (reliability, durability, history, depth), parsed."""
        try:
            items = yaml.safe_load(self.offered_qos_profiles) or []
        except yaml.YAMLError:
            return []
        profiles: list[QosDescription] = []
        for item in items if isinstance(items, list) else []:
            if not isinstance(item, dict):
                continue
            profiles.append(
                QosDescription(
                    reliability=str(item.get('reliability', 'reliable')),
                    durability=str(item.get('durability', 'volatile')),
                    history=str(item.get('history', 'keep_last')),
                    depth=int(item.get('depth', 10) or 10),
                )
            )
        return profiles


@dataclass
class _ScanResult:
    """What a linear pass over the records of a file found."""

    schemas: dict[int, Schema] = field(default_factory=dict)
    channels: dict[int, Channel] = field(default_factory=dict)
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    messages: list[tuple[int, int, int, bytes]] = field(default_factory=list)
    chunk_count: int = 0
    complete: bool = False
    cut_short: bool = False
    stop_reason: str = ''
    good_until_offset: int = 0


def _check_ros2_schemas(path: Path, schemas: Mapping[int, Schema],
                        channels: Mapping[int, Channel]) -> None:
    """Raise RecordingError unless every channel is CDR with a ros2msg schema."""
    for channel in channels.values():
        if channel.schema_id == 0 or channel.schema_id not in schemas:
            msg = (
                f'{path} is not a ROS 2 recording: topic {channel.topic!r} has no schema '
                '(a ROS 2 MCAP needs a ros2msg schema per topic)'
            )
            raise RecordingError(msg)
        schema = schemas[channel.schema_id]
        if schema.encoding != SchemaEncoding.ROS2:
            msg = (
                f'{path} is not a ROS 2 recording: schema {schema.name!r} of topic '
                f'{channel.topic!r} has encoding {schema.encoding!r}, expected '
                f'{SchemaEncoding.ROS2!r}'
            )
            raise RecordingError(msg)
        if channel.message_encoding != MessageEncoding.CDR:
            msg = (
                f'{path} is not a ROS 2 recording: topic {channel.topic!r} has message '
                f'encoding {channel.message_encoding!r}, expected {MessageEncoding.CDR!r}'
            )
            raise RecordingError(msg)


class McapRecording:
    """An MCAP recording opened for reading; tolerant of files cut short by a crash.

    A complete file is read through its summary and chunk indexes. A file without its footer
    (the recorder died before `close()`) is scanned record by record up to the last complete,
    CRC-valid chunk; `truncated` is then True and `problem` says what was lost.
    Timestamps are nanoseconds since the epoch of the clock that recorded the file.
    """

    def __init__(self, path: str | os.PathLike[str]) -> None:
        """Open and index a recording.

        Raises:
            RecordingError: Missing or unreadable file, not MCAP, or not ROS 2 (ros2msg + cdr).

        """
        self.path = Path(path)
        self.truncated = False
        self.problem: str | None = None
        self.metadata: dict[str, dict[str, str]] = {}
        self.topics: dict[str, RecordedTopic] = {}
        self.message_count = 0
        self.start_time_ns = 0
        self.end_time_ns = 0
        self.chunk_count = 0
        self._scan: _ScanResult | None = None
        self._schemas: dict[int, Schema] = {}
        self._channels: dict[int, Channel] = {}
        try:
            with self.path.open('rb') as stream:
                self._open(stream)
        except OSError as error:
            msg = f'cannot read recording {self.path}: {error.strerror or error}'
            raise RecordingError(msg) from None

    @property
    def run_metadata(self) -> dict[str, str] | None:
        """Entries of the 'uvms' metadata record (scenario, seed, parameters), if recorded."""
        return self.metadata.get(RUN_METADATA_NAME)

    def _open(self, stream: BinaryIO) -> None:
        head = stream.read(len(MCAP_MAGIC))
        if head != MCAP_MAGIC:
            what = 'is empty' if not head else 'does not start with the MCAP magic bytes'
            msg = f'{self.path} is not an MCAP file: it {what}'
            raise RecordingError(msg)
        stream.seek(-len(MCAP_MAGIC), io.SEEK_END)
        summary = None
        if stream.read(len(MCAP_MAGIC)) == MCAP_MAGIC:
            stream.seek(0)
            try:
                summary = SeekingReader(stream, validate_crcs=True).get_summary()
            except _DAMAGED_DATA_ERRORS:
                summary = None
        if summary is not None and summary.chunk_indexes:
            self._open_indexed(stream, summary.schemas, summary.channels, summary.statistics)
        else:
            self._open_scanned(stream)

    def _open_indexed(
        self,
        stream: BinaryIO,
        schemas: dict[int, Schema],
        channels: dict[int, Channel],
        statistics: Statistics | None,
    ) -> None:
        _check_ros2_schemas(self.path, schemas, channels)
        self._schemas, self._channels = schemas, channels
        stream.seek(0)
        reader = SeekingReader(stream, validate_crcs=True)
        try:
            for record in reader.iter_metadata():
                self.metadata[record.name] = dict(record.metadata)
            summary = reader.get_summary()
        except _DAMAGED_DATA_ERRORS as error:
            msg = f'{self.path} is damaged: cannot read its metadata records ({error})'
            raise RecordingError(msg) from None
        counts: dict[int, int] = {}
        if summary is not None:
            self.chunk_count = len(summary.chunk_indexes)
        if statistics is not None:
            counts = dict(statistics.channel_message_counts)
            self.message_count = statistics.message_count
            self.start_time_ns = statistics.message_start_time
            self.end_time_ns = statistics.message_end_time
        self._build_topics(counts)

    def _open_scanned(self, stream: BinaryIO) -> None:
        scan = _scan_records(stream)
        _check_ros2_schemas(self.path, scan.schemas, scan.channels)
        self._scan = scan
        self._schemas, self._channels = scan.schemas, scan.channels
        self.metadata = scan.metadata
        self.chunk_count = scan.chunk_count
        scan.messages.sort(key=lambda item: (item[1], item[0]))
        counts: dict[int, int] = {}
        for _, _, channel_id, _ in scan.messages:
            counts[channel_id] = counts.get(channel_id, 0) + 1
        self.message_count = len(scan.messages)
        if scan.messages:
            self.start_time_ns = scan.messages[0][1]
            self.end_time_ns = scan.messages[-1][1]
        self._build_topics(counts)
        if not scan.complete:
            self.truncated = True
            kept = (
                f'read {scan.chunk_count} complete chunk(s), {self.message_count} message(s) '
                + (f'up to log time {self.end_time_ns / 1e9:.6f} s' if scan.messages else '')
            ).rstrip()
            if scan.cut_short:
                self.problem = (
                    f'{self.path} was cut short (it ends without the MCAP footer and summary: '
                    f'the recorder did not close it, e.g. it was killed or crashed); {kept}; '
                    f'the data after byte {scan.good_until_offset} is lost '
                    f'({scan.stop_reason})'
                )
            else:
                self.problem = (
                    f'{self.path} is damaged at byte {scan.good_until_offset} '
                    f'({scan.stop_reason}); {kept}; the rest of the file is skipped'
                )

    def _build_topics(self, counts: Mapping[int, int]) -> None:
        for channel_id, channel in sorted(self._channels.items()):
            schema = self._schemas[channel.schema_id]
            self.topics[channel.topic] = RecordedTopic(
                topic=channel.topic,
                type_name=_ros2_type_name(schema.name),
                message_count=counts.get(channel_id, 0),
                offered_qos_profiles=channel.metadata.get('offered_qos_profiles', ''),
                type_hash=channel.metadata.get('topic_type_hash', ''),
                definition=schema.data.decode('utf-8', errors='replace'),
            )

    def messages(
        self,
        topics: Iterable[str] | None = None,
        start_ns: int | None = None,
    ) -> Iterator[RecordedMessage]:
        """Messages in log-time order (file order among equal times).

        Args:
            topics: Only these topics (default: all).
            start_ns: Only messages logged at or after this time (ns).

        Raises:
            RecordingError: A chunk of a complete file is damaged (raised when reached).

        """
        wanted = None if topics is None else set(topics)
        if self._scan is not None:
            for _, log_time, channel_id, data in self._scan.messages:
                channel = self._channels[channel_id]
                if wanted is not None and channel.topic not in wanted:
                    continue
                if start_ns is not None and log_time < start_ns:
                    continue
                yield RecordedMessage(
                    channel.topic, self.topics[channel.topic].type_name, log_time, data
                )
            return
        try:
            with self.path.open('rb') as stream:
                reader = SeekingReader(stream, validate_crcs=True)
                for _, channel, message in reader.iter_messages(
                    topics=None if wanted is None else sorted(wanted),
                    log_time_order=True,
                    starting_at=start_ns,
                ):
                    yield RecordedMessage(
                        channel.topic,
                        self.topics[channel.topic].type_name,
                        message.log_time,
                        message.data,
                    )
        except OSError as error:
            msg = f'cannot read recording {self.path}: {error.strerror or error}'
            raise RecordingError(msg) from None
        except _DAMAGED_DATA_ERRORS as error:
            msg = f'{self.path} is damaged: a chunk cannot be decoded ({error})'
            raise RecordingError(msg) from None


def _ros2_type_name(schema_name: str) -> str:
    try:
        return normalize_type_name(schema_name)
    except InterfaceError:
        return schema_name


def _damage_description(kind: str, error: BaseException) -> str:
    if isinstance(error, EndOfFile):
        return 'the file ends in the middle of a record'
    return f'the next {kind} is damaged: {str(error) or type(error).__name__}'


def _scan_records(stream: BinaryIO) -> _ScanResult:
    """Read a file record by record, keeping what precedes the first damaged or cut record."""
    result = _ScanResult()
    stream.seek(0)
    reader = StreamReader(stream, emit_chunks=True)
    order = 0
    records = reader.records
    while True:
        try:
            record = next(records)
        except StopIteration:  # pragma: no cover - the reader raises at the end instead
            result.stop_reason = 'no footer'
            break
        except _DAMAGED_DATA_ERRORS as error:
            result.stop_reason = _damage_description('record', error)
            break
        if isinstance(record, Chunk):
            try:
                inner = breakup_chunk(record, validate_crc=True)
            except _DAMAGED_DATA_ERRORS as error:
                result.stop_reason = _damage_description('chunk', error)
                break
            for item in inner:
                if isinstance(item, Schema):
                    result.schemas[item.id] = item
                elif isinstance(item, Channel):
                    result.channels[item.id] = item
                elif isinstance(item, Message):
                    result.messages.append((order, item.log_time, item.channel_id, item.data))
                    order += 1
            result.chunk_count += 1
        elif isinstance(record, Schema):
            result.schemas[record.id] = record
        elif isinstance(record, Channel):
            result.channels[record.id] = record
        elif isinstance(record, Message):
            result.messages.append((order, record.log_time, record.channel_id, record.data))
            order += 1
        elif isinstance(record, Metadata):
            result.metadata[record.name] = dict(record.metadata)
        elif isinstance(record, Footer):
            result.complete = True
            result.good_until_offset = stream.tell()
            break
        result.good_until_offset = stream.tell()
    if not result.complete:
        position = stream.tell()
        result.cut_short = position >= stream.seek(0, io.SEEK_END)
    known = set(result.channels)
    result.messages = [item for item in result.messages if item[2] in known]
    return result


def open_recording(path: str | os.PathLike[str]) -> McapRecording:
    """Open a recording for reading (see `McapRecording`).

    Raises:
        RecordingError: Missing or unreadable file, not MCAP, or not ROS 2 (ros2msg + cdr).

    """
    return McapRecording(path)


def read_recording(
    path: str | os.PathLike[str],
    topics: Iterable[str] | None = None,
) -> Iterator[RecordedMessage]:
    """Yield (topic, type_name, log_time_ns, cdr_bytes) of a recording in log-time order.

    A file cut short is read up to its last complete chunk, and a `RecordingTruncatedWarning`
    says so (no exception).

    Raises:
        RecordingError: Missing or unreadable file, not MCAP, not ROS 2, or damaged.

    """
    recording = McapRecording(path)
    if recording.problem is not None:
        warnings.warn(recording.problem, RecordingTruncatedWarning, stacklevel=2)
    return recording.messages(topics)


__all__ = [
    'DEFAULT_CHUNK_SIZE',
    'DEFAULT_FLUSH_INTERVAL_NS',
    'RUN_METADATA_NAME',
    'McapRecorder',
    'McapRecording',
    'QosDescription',
    'RecordedMessage',
    'RecordedTopic',
    'RecordingError',
    'RecordingTruncatedWarning',
    'ReplayError',
    'offered_qos_profiles_yaml',
    'open_recording',
    'read_recording',
    'run_metadata',
]
