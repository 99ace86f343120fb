"""Tests of the replay core without wall waits: pacing, looping, stopping, topic choice, diffs."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from recording_samples import GRAPH_TOPICS, graph_messages, make_message
from uvms_recording.errors import ReplayError
from uvms_recording.mcap_reader import RecordedMessage, open_recording
from uvms_recording.mcap_writer import McapRecorder
from uvms_recording.replay import ReplayOptions, play_messages, select_topics
from uvms_recording.rerun import Deviation, RerunReport, output_differences
from uvms_recording.typestore import uvms_typestore


class FakeClock:
    """Monotonic time that only moves when the code under test sleeps."""

    def __init__(self) -> None:
        self.t = 100.0
        self.sleeps: list[float] = []

    def now(self) -> float:
        """Current time (s)."""
        return self.t

    def sleep(self, seconds: float) -> None:
        """Advance the time by a positive wait (s)."""
        assert seconds > 0.0
        self.sleeps.append(seconds)
        self.t += seconds


def _messages(times_ms: list[int]) -> list[RecordedMessage]:
    return [RecordedMessage('/x', 'std_msgs/msg/Empty', t * 1_000_000, bytes([i]))
            for i, t in enumerate(times_ms)]


@pytest.mark.parametrize('rate', [0.5, 1.0, 4.0])
def test_messages_go_out_at_recorded_spacing_divided_by_rate(rate: float) -> None:
    """Message i leaves at t0 + (log_i - log_0) / rate on the replay clock."""
    clock = FakeClock()
    messages = _messages([1000, 1010, 1030, 1500])
    sent: list[tuple[float, RecordedMessage]] = []
    count = play_messages(lambda: messages, lambda m: sent.append((clock.now(), m)),
                          rate=rate, now=clock.now, sleep=clock.sleep)
    assert count == 4
    assert [m for _, m in sent] == messages
    offsets = [t - sent[0][0] for t, _ in sent]
    np.testing.assert_allclose(offsets, np.array([0.0, 0.010, 0.030, 0.500]) / rate,
                               atol=1e-12)


def test_waits_are_sliced_so_a_stop_request_is_seen_quickly() -> None:
    """No single wait exceeds 0.1 s, and a stop request ends a long wait."""
    clock = FakeClock()
    stop_after = 3
    count = play_messages(lambda: _messages([0, 60_000]), lambda m: None,
                          now=clock.now, sleep=clock.sleep,
                          keep_going=lambda: len(clock.sleeps) < stop_after)
    assert count == 1
    assert max(clock.sleeps) <= 0.1
    assert len(clock.sleeps) == stop_after


def test_late_messages_are_published_without_waiting() -> None:
    """When publishing falls behind the schedule, the replay does not sleep."""
    clock = FakeClock()

    def slow_publish(message: RecordedMessage) -> None:
        clock.t += 1.0

    count = play_messages(lambda: _messages([0, 1, 2, 3]), slow_publish,
                          now=clock.now, sleep=clock.sleep)
    assert count == 4
    assert clock.sleeps == []


def test_loop_starts_over_until_stopped() -> None:
    """With loop, passes repeat in order until keep_going turns False."""
    clock = FakeClock()
    sent: list[int] = []
    count = play_messages(lambda: _messages([0, 5, 7]), lambda m: sent.append(m.data[0]),
                          loop=True, now=clock.now, sleep=clock.sleep,
                          keep_going=lambda: len(sent) < 7)
    assert count == 7
    assert sent == [0, 1, 2, 0, 1, 2, 0]


def test_loop_over_nothing_ends() -> None:
    """Looping an empty selection returns at once instead of spinning forever."""
    clock = FakeClock()
    assert play_messages(lambda: [], lambda m: None, loop=True, now=clock.now,
                         sleep=clock.sleep) == 0


@pytest.mark.parametrize('rate', [0.0, -1.0, float('nan'), float('inf')])
def test_invalid_rate_is_rejected(rate: float) -> None:
    """A rate that is not a finite number > 0 raises ReplayError naming it."""
    with pytest.raises(ReplayError, match='rate'):
        play_messages(lambda: [], lambda m: None, rate=rate)


@pytest.fixture
def recording_path(tmp_path: Path) -> Path:
    """A small recording of every graph topic."""
    path = tmp_path / 'run.mcap'
    with McapRecorder(path) as recorder:
        for topic, type_name in GRAPH_TOPICS:
            recorder.add_topic(topic, type_name)
        for topic, _, t_ns, data in graph_messages(3):
            recorder.write(topic, data, t_ns)
    return path


def test_clock_is_replayed_only_when_asked(recording_path: Path) -> None:
    """By default every topic but /clock is replayed; --clock adds it."""
    recording = open_recording(recording_path)
    default = select_topics(recording, ReplayOptions())
    assert '/clock' not in default
    assert set(default) == {topic for topic, _ in GRAPH_TOPICS} - {'/clock'}
    assert '/clock' in select_topics(recording, ReplayOptions(clock=True))


def test_topic_filter_keeps_only_the_requested_topics(recording_path: Path) -> None:
    """--topics selects exactly those topics."""
    recording = open_recording(recording_path)
    chosen = select_topics(recording, ReplayOptions(topics=('/uvms/wrench',)))
    assert chosen == ['/uvms/wrench']


def test_unknown_topic_is_reported_with_the_recorded_ones(recording_path: Path) -> None:
    """Asking for a topic the recording lacks raises ReplayError listing what it has."""
    recording = open_recording(recording_path)
    with pytest.raises(ReplayError, match=r'/nope.*recorded topics: .*/uvms/wrench'):
        select_topics(recording, ReplayOptions(topics=('/nope',)))


def _command(joint_torques: list[float], force_x: float = 10.0) -> bytes:
    store = uvms_typestore()
    message = make_message('uvms_msgs/msg/GeneralizedForce', 0, 0)
    message.joint_torques = np.array(joint_torques)
    message.vehicle_wrench.force.x = force_x
    return bytes(store.serialize_cdr(message, 'uvms_msgs/msg/GeneralizedForce'))


def test_identical_outputs_do_not_differ() -> None:
    """Two equal commands differ by zero in every field."""
    data = _command([1.0, 2.0, 3.0])
    differences = output_differences('uvms_msgs/msg/GeneralizedForce', data, data)
    assert differences == {'vehicle force': 0.0, 'vehicle moment': 0.0, 'joint torques': 0.0}


def test_output_difference_is_the_largest_per_field() -> None:
    """The deviation of a field is its largest absolute component difference."""
    differences = output_differences('uvms_msgs/msg/GeneralizedForce',
                                     _command([1.0, 2.0, 3.0], force_x=10.0),
                                     _command([1.0, 2.5, 2.9], force_x=9.75))
    assert differences['joint torques'] == pytest.approx(0.5)
    assert differences['vehicle force'] == pytest.approx(0.25)
    assert differences['vehicle moment'] == 0.0


def test_joint_count_mismatch_is_an_infinite_deviation() -> None:
    """Commands with different numbers of joint torques differ by infinity."""
    differences = output_differences('uvms_msgs/msg/GeneralizedForce',
                                     _command([1.0, 2.0, 3.0]), _command([1.0, 2.0]))
    assert differences['joint torques'] == float('inf')


def test_report_fails_above_tolerance_and_with_missing_outputs(tmp_path: Path) -> None:
    """A re-run passes only with outputs compared, none missing, all within tolerance."""
    report = RerunReport(recording=tmp_path / 'r.mcap', tolerance=1e-6, compared=3)
    report.deviations['joint torques'] = Deviation('joint torques', 'N*m')
    report.deviations['joint torques'].update(5e-7, 1_000_000)
    assert report.passed
    report.deviations['joint torques'].update(2e-6, 2_000_000)
    assert not report.passed
    assert '> tolerance' in report.render()
    clean = RerunReport(recording=tmp_path / 'r.mcap', tolerance=1e-6, compared=3,
                        missing=[('/uvms/command/generalized_force', 0)])
    assert not clean.passed


def test_replay_progress_says_how_far_it_is_every_five_seconds_off_a_terminal() -> None:
    """Not a terminal: a line at the first message, then one per 5 s of wall time."""
    import io
    from types import SimpleNamespace

    from uvms_recording.replay import ReplayProgress

    out, clock = io.StringIO(), [0.0]
    progress = ReplayProgress(0, 20 * 10**9, file=out, now=lambda: clock[0])
    for k in range(21):  # one message per recorded second, played at rate 1
        clock[0] = float(k)
        progress(SimpleNamespace(log_time_ns=k * 10**9))  # type: ignore[arg-type]
    progress.end()
    lines = out.getvalue().splitlines()
    assert lines[0] == 'replayed 0.0 / 20.0 s of the recording'
    assert lines[-1] == 'replayed 20.0 / 20.0 s of the recording'
    assert len(lines) == 5
