"""Truncation-tolerant MCAP reader of ROS 2 recordings (ros2 profile, cdr + ros2msg).

A complete file is read through its summary and chunk indexes; a file without its footer is
scanned record by record up to its last complete, CRC-valid chunk. Timestamps are integer
nanoseconds since the epoch of the ROS clock that recorded them. Nothing here imports rclpy.
"""

from __future__ import annotations

import io
import os
import struct
import warnings
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import BinaryIO, NamedTuple

import yaml
import zstandard
from mcap.exceptions import EndOfFile, McapError
from mcap.reader import SeekingReader
from mcap.records import Channel, Chunk, Footer, Message, Metadata, Schema, Statistics
from mcap.stream_reader import StreamReader, breakup_chunk
from mcap.well_known import MessageEncoding, SchemaEncoding

from uvms_recording.errors import RecordingError, RecordingTruncatedWarning
from uvms_recording.mcap_writer import RUN_METADATA_NAME, QosDescription
from uvms_recording.typestore import InterfaceError, normalize_type_name

MCAP_MAGIC = b'\x89MCAP0\r\n'

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
    'McapRecording',
    'RecordedMessage',
    'RecordedTopic',
    'open_recording',
    'read_recording',
]
