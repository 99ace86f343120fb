"""Tests of reading recordings: log-time order, filters, truncation, damage and foreign files."""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest
from mcap.reader import make_reader
from mcap.summary import Summary
from mcap.writer import Writer
from recording_samples import GRAPH_TOPICS, graph_messages, make_cdr
from rosbags.rosbag2 import StoragePlugin
from rosbags.rosbag2 import Writer as Rosbag2Writer
from uvms_recording.errors import RecordingError, RecordingTruncatedWarning
from uvms_recording.mcap_reader import open_recording, read_recording
from uvms_recording.mcap_writer import McapRecorder
from uvms_recording.typestore import uvms_typestore

N_STEPS = 200


def _record(path: Path, messages: list[tuple[str, str, int, bytes]], **options: object) -> None:
    with McapRecorder(path, **options) as recorder:  # type: ignore[arg-type]
        for topic, type_name in GRAPH_TOPICS:
            recorder.add_topic(topic, type_name)
        for topic, _, t_ns, data in messages:
            recorder.write(topic, data, t_ns)


@pytest.fixture
def recorded(tmp_path: Path) -> tuple[Path, list[tuple[str, str, int, bytes]]]:
    """A recording in many small chunks, and what was written."""
    path = tmp_path / 'run.mcap'
    messages = graph_messages(N_STEPS)
    _record(path, messages, chunk_size=8192)
    return path, messages


def test_complete_recording_reads_back_every_message(recorded: tuple[Path, list]) -> None:
    """read_recording yields (topic, type, log time, bytes) of every message, in order."""
    path, messages = recorded
    assert [tuple(m) for m in read_recording(path)] == messages


def test_messages_come_in_log_time_order_whatever_the_write_order(tmp_path: Path) -> None:
    """Messages written out of log-time order are read back sorted by log time."""
    path = tmp_path / 'shuffled.mcap'
    messages = graph_messages(20)
    shuffled = messages[::2] + messages[1::2]
    _record(path, shuffled, chunk_size=2048)
    times = [m.log_time_ns for m in read_recording(path)]
    assert times == sorted(times)
    assert len(times) == len(messages)


def test_topic_filter_and_start_time_select_messages(recorded: tuple[Path, list]) -> None:
    """messages(topics, start_ns) keeps only those topics from that log time on."""
    path, messages = recorded
    wanted = {'/uvms/wrench', '/clock'}
    start_ns = 150_000_000
    read = [tuple(m) for m in open_recording(path).messages(wanted, start_ns=start_ns)]
    assert read == [m for m in messages if m[0] in wanted and m[2] >= start_ns]


def test_recording_lists_topics_types_and_counts(recorded: tuple[Path, list]) -> None:
    """Topics maps each topic to its type and message count; times span the messages."""
    path, messages = recorded
    recording = open_recording(path)
    assert {t: (r.type_name, r.message_count) for t, r in recording.topics.items()} == {
        topic: (type_name, N_STEPS) for topic, type_name in GRAPH_TOPICS
    }
    assert (recording.start_time_ns, recording.end_time_ns) == (messages[0][2], messages[-1][2])
    assert not recording.truncated
    assert recording.problem is None


def _summary(path: Path) -> Summary:
    with path.open('rb') as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None
    return summary


@pytest.mark.parametrize('fraction', [0.05, 0.2, 0.5, 0.77, 0.99])
def test_cut_file_is_read_up_to_its_last_complete_chunk(
    recorded: tuple[Path, list], tmp_path: Path, fraction: float
) -> None:
    """A file cut anywhere in its chunks yields a prefix of the messages, flagged truncated."""
    path, messages = recorded
    data_end = _summary(path).chunk_indexes[-1].chunk_start_offset
    cut = tmp_path / 'cut.mcap'
    cut.write_bytes(path.read_bytes()[: int(data_end * fraction)])
    recording = open_recording(cut)
    read = [tuple(m) for m in recording.messages()]
    assert recording.truncated
    assert 0 < len(read) < len(messages)
    assert read == messages[: len(read)]


def test_file_cut_inside_its_summary_keeps_every_message(
    recorded: tuple[Path, list], tmp_path: Path
) -> None:
    """Losing only the summary loses no message, but the file is still flagged truncated."""
    path, messages = recorded
    cut = tmp_path / 'cut.mcap'
    cut.write_bytes(path.read_bytes()[:-100])
    recording = open_recording(cut)
    assert recording.truncated
    assert [tuple(m) for m in recording.messages()] == messages


def test_cut_file_report_names_the_file_and_what_survived(
    recorded: tuple[Path, list], tmp_path: Path
) -> None:
    """The truncation report says 'cut short', names the file and the messages kept."""
    path, _ = recorded
    cut = tmp_path / 'cut.mcap'
    cut.write_bytes(path.read_bytes()[:-100])
    recording = open_recording(cut)
    assert recording.problem is not None
    assert 'cut short' in recording.problem
    assert str(cut) in recording.problem
    assert f'{recording.message_count} message(s)' in recording.problem


def test_read_recording_warns_once_about_a_cut_file(
    recorded: tuple[Path, list], tmp_path: Path
) -> None:
    """read_recording of a cut file emits one RecordingTruncatedWarning, no exception."""
    path, _ = recorded
    cut = tmp_path / 'cut.mcap'
    cut.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter('always')
        messages = list(read_recording(cut))
    assert messages
    assert [w.category for w in caught] == [RecordingTruncatedWarning]


def test_file_cut_inside_the_header_has_no_messages_but_opens(
    recorded: tuple[Path, list], tmp_path: Path
) -> None:
    """A file cut right after the magic bytes opens as truncated with no messages."""
    path, _ = recorded
    cut = tmp_path / 'cut.mcap'
    cut.write_bytes(path.read_bytes()[:12])
    recording = open_recording(cut)
    assert recording.truncated
    assert list(recording.messages()) == []


def test_damaged_chunk_of_a_complete_file_raises_recording_error(
    recorded: tuple[Path, list], tmp_path: Path
) -> None:
    """Bytes flipped inside a chunk give a RecordingError saying the file is damaged."""
    path, _ = recorded
    data = bytearray(path.read_bytes())
    chunk = _summary(path).chunk_indexes[3]
    middle = chunk.chunk_start_offset + chunk.chunk_length // 2
    data[middle : middle + 64] = bytes(64)
    damaged = tmp_path / 'damaged.mcap'
    damaged.write_bytes(bytes(data))
    with pytest.raises(RecordingError, match='damaged'):
        list(open_recording(damaged).messages())


def test_damaged_chunk_of_a_cut_file_ends_the_read_with_a_damage_report(
    recorded: tuple[Path, list], tmp_path: Path
) -> None:
    """Without a summary, reading stops before a damaged chunk and says 'damaged', not 'cut'."""
    path, messages = recorded
    data = bytearray(path.read_bytes()[:-100])
    chunk = _summary(path).chunk_indexes[3]
    middle = chunk.chunk_start_offset + chunk.chunk_length // 2
    data[middle : middle + 64] = bytes(64)
    damaged = tmp_path / 'damaged.mcap'
    damaged.write_bytes(bytes(data))
    recording = open_recording(damaged)
    assert recording.problem is not None
    assert f'is damaged at byte {chunk.chunk_start_offset}' in recording.problem
    assert [tuple(m) for m in recording.messages()] == messages[: recording.message_count]


def test_garbage_file_is_not_mcap(tmp_path: Path) -> None:
    """A file that is not MCAP raises RecordingError naming it."""
    path = tmp_path / 'notes.mcap'
    path.write_text('these are not the bytes you are looking for\n' * 10)
    with pytest.raises(RecordingError, match='not an MCAP file') as info:
        open_recording(path)
    assert str(path) in str(info.value)


def test_empty_file_is_not_mcap(tmp_path: Path) -> None:
    """An empty file raises RecordingError saying it is empty."""
    path = tmp_path / 'empty.mcap'
    path.write_bytes(b'')
    with pytest.raises(RecordingError, match='empty'):
        open_recording(path)


def test_missing_file_is_reported(tmp_path: Path) -> None:
    """A missing file raises RecordingError naming it, at open time."""
    path = tmp_path / 'absent.mcap'
    with pytest.raises(RecordingError, match=r'absent\.mcap'):
        read_recording(path)


def test_mcap_with_non_ros2msg_schema_is_rejected(tmp_path: Path) -> None:
    """An MCAP whose schema is not ros2msg raises RecordingError naming schema and encoding."""
    path = tmp_path / 'json.mcap'
    with path.open('wb') as stream:
        writer = Writer(stream)
        writer.start(profile='', library='test')
        schema_id = writer.register_schema('Thing', 'jsonschema', b'{}')
        channel_id = writer.register_channel('/thing', 'json', schema_id)
        writer.add_message(channel_id, log_time=0, data=b'{}', publish_time=0)
        writer.finish()
    with pytest.raises(RecordingError, match=r"'Thing'.*'jsonschema'"):
        open_recording(path)


def test_recording_written_by_rosbags_is_read(tmp_path: Path) -> None:
    """An MCAP written by rosbags' own rosbag2 writer reads back with our reader."""
    bag = tmp_path / 'bag'
    store = uvms_typestore()
    data = make_cdr('geometry_msgs/msg/WrenchStamped', 5, 0)
    with Rosbag2Writer(bag, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connection = writer.add_connection('/uvms/wrench', 'geometry_msgs/msg/WrenchStamped',
                                           typestore=store)
        writer.write(connection, 5, data)
        writer.write(connection, 9, data)
    (mcap_file,) = bag.glob('*.mcap')
    read = [tuple(m) for m in read_recording(mcap_file)]
    assert read == [('/uvms/wrench', 'geometry_msgs/msg/WrenchStamped', 5, data),
                    ('/uvms/wrench', 'geometry_msgs/msg/WrenchStamped', 9, data)]


def test_run_metadata_survives_truncation(tmp_path: Path) -> None:
    """The 'uvms' record written at open is still there when the file is cut short."""
    path = tmp_path / 'run.mcap'
    with McapRecorder(path, metadata={'scenario': 'free_motion', 'seed': '1'}) as recorder:
        recorder.add_topic('/clock', 'rosgraph_msgs/msg/Clock')
        for k in range(1000):
            recorder.write('/clock', make_cdr('rosgraph_msgs/msg/Clock', k, k), k)
    cut = tmp_path / 'cut.mcap'
    cut.write_bytes(path.read_bytes()[:-200])
    assert open_recording(cut).run_metadata == {'scenario': 'free_motion', 'seed': '1'}
