"""Write-then-read tests of McapRecorder, read back by the mcap library and by rosbags."""

from __future__ import annotations

import shutil
from collections import Counter
from pathlib import Path

import pytest
import yaml
from mcap.reader import make_reader
from mcap.records import Chunk, Metadata
from mcap.stream_reader import StreamReader
from recording_samples import GRAPH_TOPICS, graph_messages, make_message
from rosbags.highlevel import AnyReader
from rosbags.interfaces import QosDurability, QosReliability
from uvms_recording.errors import RecordingError
from uvms_recording.mcap_reader import open_recording
from uvms_recording.mcap_writer import (
    RUN_METADATA_NAME,
    McapRecorder,
    QosDescription,
    run_metadata,
)
from uvms_recording.typestore import type_hash, uvms_typestore

N_STEPS = 50


def _record(
    path: Path, n_steps: int = N_STEPS, **options: object
) -> list[tuple[str, str, int, bytes]]:
    messages = graph_messages(n_steps)
    with McapRecorder(path, **options) as recorder:  # type: ignore[arg-type]
        for topic, type_name in GRAPH_TOPICS:
            recorder.add_topic(topic, type_name)
        for topic, _, t_ns, data in messages:
            recorder.write(topic, data, t_ns)
    return messages


@pytest.fixture
def recorded(tmp_path: Path) -> tuple[Path, list[tuple[str, str, int, bytes]]]:
    """A closed recording of N_STEPS steps of every graph topic, and what was written."""
    path = tmp_path / 'run.mcap'
    return path, _record(path)


def test_header_declares_the_ros2_profile(recorded: tuple[Path, list]) -> None:
    """The MCAP header's profile is 'ros2' and the library names the writer."""
    path, _ = recorded
    with path.open('rb') as stream:
        header = make_reader(stream).get_header()
    assert header.profile == 'ros2'
    assert header.library.startswith('uvms_recording/')


def test_schemas_are_ros2msg_with_the_full_definition(recorded: tuple[Path, list]) -> None:
    """Each schema is named 'pkg/msg/Type', encoded 'ros2msg', with generate_msgdef's text."""
    path, _ = recorded
    with path.open('rb') as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None
    schemas = {schema.name: schema for schema in summary.schemas.values()}
    assert set(schemas) == {type_name for _, type_name in GRAPH_TOPICS}
    for name, schema in schemas.items():
        assert schema.encoding == 'ros2msg'
        assert schema.data.decode() == uvms_typestore().generate_msgdef(name, ros_version=2)[0]


def test_channels_are_cdr_with_qos_and_type_hash(recorded: tuple[Path, list]) -> None:
    """Each channel is 'cdr' with offered_qos_profiles (YAML list) and its RIHS01 hash."""
    path, _ = recorded
    with path.open('rb') as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None
    for channel in summary.channels.values():
        schema = summary.schemas[channel.schema_id]
        assert channel.message_encoding == 'cdr'
        assert channel.metadata['topic_type_hash'] == type_hash(schema.name)
        profiles = yaml.safe_load(channel.metadata['offered_qos_profiles'])
        assert isinstance(profiles, list)
        assert len(profiles) == 1
        assert profiles[0]['reliability'] == 'reliable'
        assert profiles[0]['deadline'] == {'sec': 9223372036, 'nsec': 854775807}


def test_statistics_count_every_message_per_channel(recorded: tuple[Path, list]) -> None:
    """The Statistics record counts messages per channel and spans first to last log time."""
    path, messages = recorded
    with path.open('rb') as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None
    statistics = summary.statistics
    assert statistics is not None
    assert statistics.message_count == len(messages)
    counts = {summary.channels[cid].topic: n for cid, n in
              statistics.channel_message_counts.items()}
    assert counts == Counter(topic for topic, *_ in messages)
    assert statistics.message_start_time == messages[0][2]
    assert statistics.message_end_time == messages[-1][2]
    assert statistics.schema_count == len(GRAPH_TOPICS)
    assert statistics.channel_count == len(GRAPH_TOPICS)


def test_no_rosbag2_metadata_record_is_written(recorded: tuple[Path, list]) -> None:
    """The file holds no 'rosbag2' metadata record (a partial one makes ros2 bag throw)."""
    path, _ = recorded
    with path.open('rb') as stream:
        names = [record.name for record in make_reader(stream).iter_metadata()]
    assert 'rosbag2' not in names


def test_mcap_reader_returns_the_written_bytes_in_order(recorded: tuple[Path, list]) -> None:
    """The mcap library reads back every message's bytes, topic and log time, in order."""
    path, messages = recorded
    with path.open('rb') as stream:
        read = [(channel.topic, schema.name, message.log_time, message.data)
                for schema, channel, message in make_reader(stream).iter_messages()]
    assert read == messages


def test_sequence_numbers_count_up_per_channel(recorded: tuple[Path, list]) -> None:
    """Each channel's messages carry sequence numbers 1, 2, 3, ..."""
    path, _ = recorded
    sequences: dict[str, list[int]] = {}
    with path.open('rb') as stream:
        for _, channel, message in make_reader(stream).iter_messages(log_time_order=False):
            sequences.setdefault(channel.topic, []).append(message.sequence)
    for values in sequences.values():
        assert values == list(range(1, N_STEPS + 1))


def test_rosbags_decodes_the_messages_that_were_written(recorded: tuple[Path, list]) -> None:
    """The rosbags AnyReader, typed from the file's own schemas, decodes the originals."""
    path, messages = recorded
    decoded = []
    with AnyReader([path]) as reader:
        for connection, t_ns, raw in reader.messages():
            decoded.append((connection.topic, t_ns, reader.deserialize(raw, connection.msgtype)))
    assert len(decoded) == len(messages)
    store = uvms_typestore()
    for (topic, t_ns, value), (exp_topic, type_name, exp_t, _) in zip(decoded, messages,
                                                                      strict=True):
        assert (topic, t_ns) == (exp_topic, exp_t)
        expected = make_message(type_name, exp_t, exp_t // 1_000_000)
        assert store.serialize_cdr(value, type_name) == store.serialize_cdr(expected, type_name)


def test_rosbags_reads_the_offered_qos(tmp_path: Path) -> None:
    """The rosbags reader parses offered_qos_profiles into the QoS given to add_topic."""
    path = tmp_path / 'tf.mcap'
    with McapRecorder(path) as recorder:
        recorder.add_topic('/tf_static', 'tf2_msgs/msg/TFMessage',
                           QosDescription(durability='transient_local', depth=1))
        recorder.add_topic('/clock', 'rosgraph_msgs/msg/Clock',
                           QosDescription(reliability='best_effort'))
        recorder.write('/clock', bytes(uvms_typestore().serialize_cdr(
            make_message('rosgraph_msgs/msg/Clock', 0, 0), 'rosgraph_msgs/msg/Clock')), 0)
    with AnyReader([path]) as reader:
        qos = {c.topic: c.ext.offered_qos_profiles[0] for c in reader.connections}  # type: ignore[union-attr]
    assert qos['/tf_static'].durability == QosDurability.TRANSIENT_LOCAL
    assert qos['/tf_static'].depth == 1
    assert qos['/clock'].reliability == QosReliability.BEST_EFFORT


@pytest.mark.parametrize('compression', ['zstd', 'lz4', 'none'])
def test_chunks_use_the_chosen_compression(tmp_path: Path, compression: str) -> None:
    """Every chunk is compressed as asked ('' in the file for 'none')."""
    path = tmp_path / f'{compression}.mcap'
    _record(path, compression=compression, chunk_size=4096)
    with path.open('rb') as stream:
        chunks = [r for r in StreamReader(stream, emit_chunks=True).records
                  if isinstance(r, Chunk)]
    assert len(chunks) > 1
    assert {chunk.compression for chunk in chunks} == {'' if compression == 'none'
                                                        else compression}


def test_flush_interval_closes_a_chunk_per_span_of_log_time(tmp_path: Path) -> None:
    """With a 10 ms flush interval, 50 ms of 1 kHz data lands in at least 5 chunks."""
    path = tmp_path / 'interval.mcap'
    _record(path, flush_interval_ns=10_000_000)
    assert open_recording(path).chunk_count >= 5


def test_run_metadata_is_stored_in_the_uvms_record(tmp_path: Path) -> None:
    """The scenario, seed and parameter YAML are in the 'uvms' metadata record."""
    path = tmp_path / 'meta.mcap'
    entries = run_metadata('case1_ke1e4', 7, '/uvms/controller:\n  ros__parameters: {}\n')
    with McapRecorder(path, metadata=entries):
        pass
    with path.open('rb') as stream:
        records = list(make_reader(stream).iter_metadata())
    assert [(r.name, r.metadata) for r in records] == [(RUN_METADATA_NAME, entries)]
    assert isinstance(records[0], Metadata)


def test_file_of_a_recorder_that_never_closed_is_readable_up_to_its_last_chunk(
    tmp_path: Path,
) -> None:
    """A copy taken before close() (as a crash leaves it) yields the flushed messages."""
    path = tmp_path / 'live.mcap'
    messages = graph_messages(N_STEPS)
    recorder = McapRecorder(path, flush_interval_ns=5_000_000)
    for topic, type_name in GRAPH_TOPICS:
        recorder.add_topic(topic, type_name)
    for topic, _, t_ns, data in messages:
        recorder.write(topic, data, t_ns)
    crashed = tmp_path / 'crashed.mcap'
    shutil.copyfile(path, crashed)
    recorder.close()

    recording = open_recording(crashed)
    read = [tuple(m) for m in recording.messages()]
    assert recording.truncated
    assert len(read) >= len(messages) - 6 * len(GRAPH_TOPICS)
    assert read == messages[: len(read)]


def test_empty_recording_keeps_its_topics(tmp_path: Path) -> None:
    """A recording closed without messages lists its topics with zero messages."""
    path = tmp_path / 'empty.mcap'
    with McapRecorder(path) as recorder:
        recorder.add_topic('/uvms/wrench', 'geometry_msgs/msg/WrenchStamped')
    recording = open_recording(path)
    assert not recording.truncated
    assert recording.topics['/uvms/wrench'].message_count == 0


def test_unknown_type_is_rejected_with_topic_type_and_file(tmp_path: Path) -> None:
    """add_topic with an unknown type raises RecordingError naming topic, type and file."""
    path = tmp_path / 'bad.mcap'
    with McapRecorder(path) as recorder, pytest.raises(RecordingError) as info:
        recorder.add_topic('/x', 'nope_msgs/msg/Nothing')
    assert all(part in str(info.value) for part in ('/x', 'nope_msgs/msg/Nothing', str(path)))


def test_writing_to_an_unregistered_topic_is_rejected(tmp_path: Path) -> None:
    """write() to a topic without add_topic raises RecordingError naming the topic."""
    with McapRecorder(tmp_path / 'x.mcap') as recorder, pytest.raises(RecordingError,
                                                                      match='/nowhere'):
        recorder.write('/nowhere', b'\x00\x01\x00\x00', 0)


def test_topic_cannot_be_added_twice(tmp_path: Path) -> None:
    """A second add_topic for the same topic raises RecordingError."""
    with McapRecorder(tmp_path / 'x.mcap') as recorder:
        recorder.add_topic('/clock', 'rosgraph_msgs/msg/Clock')
        with pytest.raises(RecordingError, match='already added'):
            recorder.add_topic('/clock', 'rosgraph_msgs/msg/Clock')


def test_negative_log_time_is_rejected(tmp_path: Path) -> None:
    """MCAP times are unsigned: a negative log time raises RecordingError."""
    with McapRecorder(tmp_path / 'x.mcap') as recorder:
        recorder.add_topic('/clock', 'rosgraph_msgs/msg/Clock')
        with pytest.raises(RecordingError, match='< 0'):
            recorder.write('/clock', b'\x00\x01\x00\x00' + bytes(8), -1)


def test_writing_after_close_is_rejected(tmp_path: Path) -> None:
    """write() after close() raises RecordingError saying the file is closed."""
    recorder = McapRecorder(tmp_path / 'x.mcap')
    recorder.add_topic('/clock', 'rosgraph_msgs/msg/Clock')
    recorder.close()
    with pytest.raises(RecordingError, match='already closed'):
        recorder.write('/clock', b'\x00\x01\x00\x00' + bytes(8), 0)


def test_close_is_idempotent(tmp_path: Path) -> None:
    """A second close() leaves the complete file as it was."""
    path = tmp_path / 'x.mcap'
    recorder = McapRecorder(path)
    recorder.close()
    size = path.stat().st_size
    recorder.close()
    assert path.stat().st_size == size
    assert not open_recording(path).truncated


def test_unknown_compression_is_rejected(tmp_path: Path) -> None:
    """An unknown compression name raises RecordingError listing the valid ones."""
    with pytest.raises(RecordingError, match="'lz4', 'none', 'zstd'"):
        McapRecorder(tmp_path / 'x.mcap', compression='gzip')  # type: ignore[arg-type]


def test_uncreatable_file_is_reported(tmp_path: Path) -> None:
    """A path in a missing directory raises RecordingError naming it."""
    path = tmp_path / 'missing' / 'x.mcap'
    with pytest.raises(RecordingError, match=str(path)):
        McapRecorder(path)
