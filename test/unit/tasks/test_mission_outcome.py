"""The mission's outcome file: what ``uvms launch`` reads to say what failed."""

from __future__ import annotations

from pathlib import Path

from action_msgs.msg import GoalStatus
from uvms_tasks.goals import TaskOutcome
from uvms_tasks.mission_outcome import MissionOutcome, read_outcome, write_outcome

from uvms_msgs.action import ContactTask


def test_outcome_round_trips_through_its_file_and_reads_as_one_line(tmp_path: Path) -> None:
    """Written then read, the outcome gives the launcher's line: code and the result's text."""
    path = tmp_path / 'outcome.json'
    write_outcome(path, MissionOutcome(False, 'press', 'NO_CONTACT',
                                       'the path ended without contact'))
    outcome = read_outcome(path)
    assert outcome == MissionOutcome(False, 'press', 'NO_CONTACT',
                                     'the path ended without contact')
    assert outcome.line() == 'mission failed: NO_CONTACT (the path ended without contact)'
    assert MissionOutcome(False, 'press', 'CANCELED').line() == 'mission failed: CANCELED'
    assert not list(tmp_path.glob('*.partial'))


def test_a_missing_or_broken_outcome_file_reads_as_none(tmp_path: Path) -> None:
    """No file (a mission that crashed) or half a file: None, never an exception."""
    assert read_outcome(tmp_path / 'none.json') is None
    (tmp_path / 'broken.json').write_text('{"succeeded": fa', encoding='utf-8')
    assert read_outcome(tmp_path / 'broken.json') is None


def test_task_outcome_names_the_result_code_a_refusal_and_a_bare_status() -> None:
    """The code of a result, REJECTED for a refused goal, the status name without a result."""
    result = ContactTask.Result(error_code=ContactTask.Result.TRACKING_LIMIT,
                                error_string='tracking error 0.301 m')
    aborted = TaskOutcome('half', GoalStatus.STATUS_ABORTED, result)
    assert (aborted.code, aborted.message) == ('TRACKING_LIMIT', 'tracking error 0.301 m')
    assert TaskOutcome('half', GoalStatus.STATUS_ABORTED, rejected=True).code == 'REJECTED'
    assert TaskOutcome('half', GoalStatus.STATUS_CANCELED).code == 'CANCELED'
