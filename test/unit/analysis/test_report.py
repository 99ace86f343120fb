"""Tests of `uvms report` (uvms_analysis.report): rows, values, formats and errors."""

from __future__ import annotations

import csv
import io
from pathlib import Path

import pytest
from uvms_analysis.report import main


def run_report(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    """Run the CLI; returns (status, stdout, stderr)."""
    status = main(list(argv))
    captured = capsys.readouterr()
    return status, captured.out, captured.err


def csv_rows(text: str) -> dict[str, dict[str, str]]:
    """CSV report rows by run name."""
    return {row['run']: row for row in csv.DictReader(io.StringIO(text))}


def test_csv_report_has_one_row_per_run_named_by_scenario_or_stem(
    capsys: pytest.CaptureFixture[str], contact_recording: Path, free_motion_recording: Path
) -> None:
    """Two recordings give two rows: the scenario name and the file stem."""
    status, out, _ = run_report(
        capsys, str(contact_recording), str(free_motion_recording), '--format', 'csv'
    )
    assert status == 0
    assert list(csv_rows(out)) == ['case1_synthetic', 'free_motion_run']


def test_csv_report_values_match_the_known_contact_run(
    capsys: pytest.CaptureFixture[str], contact_recording: Path
) -> None:
    """Values appear in the units the column names state (N, s, %, mm, deg)."""
    _, out, _ = run_report(capsys, str(contact_recording), '--format', 'csv')
    row = csv_rows(out)['case1_synthetic']
    assert float(row['desired_force_N']) == pytest.approx(150.0)
    assert float(row['peak_force_N']) == pytest.approx(180.0)
    assert float(row['overshoot_percent']) == pytest.approx(20.0)
    assert float(row['first_contact_s']) == pytest.approx(2.0)
    assert float(row['settling_time_s']) == pytest.approx(0.3773, abs=0.002)
    assert float(row['max_error_y_contact_mm']) == pytest.approx(1.0)
    assert float(row['max_error_z_mm']) == pytest.approx(3.0)
    assert float(row['vehicle_displacement_mm']) == pytest.approx(5.0)
    assert float(row['vehicle_rotation_deg']) == pytest.approx(1.14592, abs=1e-4)
    assert row['force_source'] == 'contact'


def test_free_motion_row_reports_force_metrics_as_not_applicable(
    capsys: pytest.CaptureFixture[str], free_motion_recording: Path
) -> None:
    """Force metrics read n/a; the tracking error is a number."""
    _, out, _ = run_report(capsys, str(free_motion_recording), '--format', 'csv')
    row = csv_rows(out)['free_motion_run']
    for key in ('peak_force_N', 'overshoot_percent', 'settling_time_s', 'first_contact_s'):
        assert row[key] == 'n/a', key
    assert float(row['tracking_error_mm']) == pytest.approx(0.7071, abs=1e-4)


def test_text_report_shows_units_and_a_row_per_run(
    capsys: pytest.CaptureFixture[str], contact_recording: Path
) -> None:
    """The default table has unit lines and the run's values with fixed decimals."""
    status, out, _ = run_report(capsys, str(contact_recording))
    assert status == 0
    lines = out.splitlines()
    assert any('[N]' in line and '[mm]' in line and '[deg]' in line for line in lines)
    row = next(line for line in lines if line.startswith('case1_synthetic'))
    # task n/a: a recording without task records is one row for the whole run
    assert row.split()[1:6] == [str(contact_recording), 'n/a', '150.0', '2.000', '1']


def test_markdown_report_is_a_table_with_aligned_columns(
    capsys: pytest.CaptureFixture[str], contact_recording: Path
) -> None:
    """Header, separator and one row, all with the same number of cells."""
    _, out, _ = run_report(capsys, str(contact_recording), '--format', 'markdown')
    table = [line for line in out.splitlines() if line.startswith('|')]
    assert len(table) == 3
    assert len({line.count(' | ') for line in table}) == 1
    assert table[2].startswith(f'| case1_synthetic | {contact_recording} | n/a | 150.0 |')


@pytest.mark.parametrize('fmt', ['text', 'markdown', 'csv'])
def test_two_recordings_of_one_scenario_give_two_distinct_rows(
    capsys: pytest.CaptureFixture[str], contact_recording: Path, tmp_path: Path, fmt: str
) -> None:
    """Runs that share a scenario name are told apart by their file in every format."""
    copy = tmp_path / 'live.mcap'
    copy.write_bytes(contact_recording.read_bytes())
    status, out, _ = run_report(capsys, str(contact_recording), str(copy), '--format', fmt)
    assert status == 0
    rows = [line for line in out.splitlines() if 'case1_synthetic' in line]
    assert len(rows) == 2
    assert len(set(rows)) == 2
    assert str(contact_recording) in rows[0] and str(copy) in rows[1]
    if fmt == 'csv':
        files = [row['file'] for row in csv.DictReader(io.StringIO(out))]
        assert files == [str(contact_recording), str(copy)]


def test_missing_file_fails_with_a_message_and_no_traceback(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """Exit status 1 and one line on stderr naming the file."""
    status, out, err = run_report(capsys, str(tmp_path / 'absent.mcap'))
    assert status == 1
    assert out == ''
    assert 'absent.mcap' in err and 'Traceback' not in err


def test_corrupt_file_fails_but_readable_runs_are_still_reported(
    capsys: pytest.CaptureFixture[str], contact_recording: Path, tmp_path: Path
) -> None:
    """A garbage file makes the status 1; the good recording still gets its row."""
    bad = tmp_path / 'garbage.mcap'
    bad.write_bytes(b'\x00' * 64)
    status, out, err = run_report(capsys, str(bad), str(contact_recording), '--format', 'csv')
    assert status == 1
    assert 'garbage.mcap' in err and 'Traceback' not in err
    assert list(csv_rows(out)) == ['case1_synthetic']


def test_unknown_format_is_a_usage_error(
    capsys: pytest.CaptureFixture[str], contact_recording: Path
) -> None:
    """Argparse rejects the format with status 2 instead of raising SystemExit."""
    status, _, err = run_report(capsys, str(contact_recording), '--format', 'html')
    assert status == 2
    assert 'html' in err


def test_truncated_recording_is_reported_with_a_warning(
    capsys: pytest.CaptureFixture[str], contact_recording: Path, tmp_path: Path
) -> None:
    """A file cut short still gets its row (status 0), and stderr says it was cut short."""
    cut = tmp_path / 'cut.mcap'
    data = contact_recording.read_bytes()
    cut.write_bytes(data[: len(data) // 2])
    status, out, err = run_report(capsys, str(cut), '--format', 'csv')
    assert status == 0
    assert list(csv_rows(out)) == ['case1_synthetic']
    assert 'warning' in err and 'cut short' in err


def test_report_names_the_robot_a_run_used() -> None:
    """The simulator's robot_name from the recorded parameters, a path as it was given."""
    from uvms_analysis.metrics import run_robot
    from uvms_analysis.report import COLUMNS

    parameters = ('/uvms/controller:\n  ros__parameters:\n    robot_name: paper_uvms\n'
                  '/uvms/simulator:\n  ros__parameters:\n    robot_name: ./my_robot\n')
    assert run_robot({'uvms': {'parameters': parameters}}) == './my_robot'
    assert run_robot({}) is None
    assert run_robot({'uvms': {'parameters': ': not yaml ['}}) is None
    assert 'robot' in [column.key for column in COLUMNS]


def test_report_of_a_recording_without_task_record_says_so_on_stderr(
    capsys: pytest.CaptureFixture[str], contact_recording: Path
) -> None:
    """A per-recording row (no task record) is named on stderr, not passed off as a task's."""
    status, out, err = run_report(capsys, str(contact_recording), '--format', 'csv')
    assert status == 0
    assert csv_rows(out)['case1_synthetic']['task'] == 'n/a'
    assert str(contact_recording) in err
    assert 'no task record (/uvms/controller/task_record)' in err


def test_report_warns_when_a_run_that_sent_tasks_holds_no_task_record(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    """A recorded mission without any task record is a warning: the record was lost."""
    from analysis_recordings import contact_signals, write_signals

    path = write_signals(tmp_path / 'hand.mcap', contact_signals(), scenario='case1_ke1e4')
    write_signals(tmp_path / 'mission.mcap', contact_signals(), scenario='case1_ke1e4',
                  mission='mission:\n- force_n: 150.0\n')
    _, _, err = run_report(capsys, str(path))
    assert err.startswith('uvms report: note: ')
    _, _, err = run_report(capsys, str(tmp_path / 'mission.mcap'))
    assert 'uvms report: warning: the run sent contact tasks' in err


def test_report_names_the_default_robot_when_the_parameters_name_none() -> None:
    """Recorded node parameters without robot_name: the nodes loaded the default robot."""
    from uvms_analysis.metrics import run_robot

    from uvms_description import DEFAULT_ROBOT

    parameters = '/uvms/controller:\n  ros__parameters:\n    control_rate_hz: 500.0\n'
    assert run_robot({'uvms': {'parameters': parameters}}) == DEFAULT_ROBOT == 'paper_uvms'
