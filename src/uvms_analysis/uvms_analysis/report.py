"""`uvms report`: a table of the performance metrics of one or more recordings."""

from __future__ import annotations

import argparse
import csv
import io
import math
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from uvms_analysis.estimate_errors import EstimateErrors, estimate_errors, format_estimate_errors
from uvms_analysis.metrics import (
    IMPACT_WINDOW_S,
    SETTLING_BAND,
    TRACKING_START_S,
    RunMetrics,
    compute_metrics,
    task_metrics,
)
from uvms_analysis.series import AnalysisError, Run, load_run
from uvms_analysis.tasks import TOPIC_TASK_RECORD

FORMATS = ('text', 'markdown', 'csv')
NOT_APPLICABLE = 'n/a'


@dataclass(frozen=True)
class Column:
    """One column of the report.

    Attributes:
        label: Short heading for text and markdown tables.
        unit: Unit shown under or beside the heading ('' for none).
        key: Machine name for CSV, with the unit as suffix.
        value: Extracts the value (in the shown unit) from the metrics; None is n/a.
        digits: Decimals in text and markdown tables.
        short: Characters of a text value shown in text and markdown tables (0: all; CSV
            always has all).
    """

    label: str
    unit: str
    key: str
    value: Callable[[RunMetrics], float | int | str | None]
    digits: int = 1
    short: int = 0


def _scaled(name: str, factor: float) -> Callable[[RunMetrics], float | None]:
    """Getter of a metric multiplied by ``factor`` (unit conversion), None stays None."""

    def get(metrics: RunMetrics) -> float | None:
        value = getattr(metrics, name)
        return None if value is None else value * factor

    return get


def _attr(name: str) -> Callable[[RunMetrics], float | int | str | None]:
    """Getter of a metric as it is."""
    return lambda metrics: getattr(metrics, name)


COLUMNS = (
    Column('run', '', 'run', _attr('name')),
    Column('file', '', 'file', _attr('file')),
    Column('task', '', 'task', _attr('task'), short=8),
    Column('F_d', 'N', 'desired_force_N', _attr('desired_force')),
    Column('first\ncontact', 's', 'first_contact_s', _attr('first_contact_time'), 3),
    Column('contacts', '', 'contact_count', _attr('contact_count'), 0),
    Column('contact\ntime', 's', 'contact_duration_s', _attr('contact_duration'), 3),
    Column('peak\nF', 'N', 'peak_force_N', _attr('peak_force')),
    Column('over-\nshoot', '%', 'overshoot_percent', _attr('overshoot')),
    Column('impact\npeak F', 'N', 'impact_peak_force_N', _attr('impact_peak_force')),
    Column('settling\ntime', 's', 'settling_time_s', _attr('settling_time'), 3),
    Column('RMS\nF error', 'N', 'force_rms_error_N', _attr('force_rms_error'), 2),
    Column(
        'max e_y\ncontact', 'mm', 'max_error_y_contact_mm', _scaled('max_error_y_contact', 1e3), 2
    ),
    Column(
        'max e_z\ncontact', 'mm', 'max_error_z_contact_mm', _scaled('max_error_z_contact', 1e3), 2
    ),
    Column('max e_y\noverall', 'mm', 'max_error_y_mm', _scaled('max_error_y', 1e3), 2),
    Column('max e_z\noverall', 'mm', 'max_error_z_mm', _scaled('max_error_z', 1e3), 2),
    Column('tracking\nerror', 'mm', 'tracking_error_mm', _scaled('tracking_error', 1e3), 2),
    Column(
        'vehicle\ndisplace',
        'mm',
        'vehicle_displacement_mm',
        _scaled('vehicle_displacement', 1e3),
        1,
    ),
    Column(
        'vehicle\nrotation',
        'deg',
        'vehicle_rotation_deg',
        _scaled('vehicle_rotation', 180.0 / math.pi),
        2,
    ),
    Column('current\nmean', 'm/s', 'current_speed_m_s', _attr('current_speed'), 3),
    Column('current\nmax', 'm/s', 'current_speed_max_m_s', _attr('current_speed_max'), 3),
    Column('thrust\nscale', '', 'saturation_scale_min', _attr('saturation_scale_min'), 3),
    Column('force\nfrom', '', 'force_source', _attr('force_source')),
    Column('robot', '', 'robot', _attr('robot')),
)
#: Columns that name a run rather than measure it (left-aligned; no sweep metric).
LABEL_KEYS = ('run', 'robot', 'file', 'task', 'force_source')
_LEFT_ALIGNED = ('run', 'robot', 'file', 'task')

LEGEND = (
    'run: scenario of the recording (else its file name); file: the recording as given.',
    'robot: the robot folder the run used (its name, or the path given with --robot).',
    'task: goal id of a contact task (first 8 hex digits; all 32 in CSV): one row per task,',
    '   from its first to its last control step, F_d its force_n; --force-source controller:',
    "   force metrics as its result's.",
    "F: contact force along the wall normal (map_ned x; a task's normal); force from: contact =",
    "   simulator ground truth (/uvms/contact), controller = the controller's measured F_e.",
    'F_d: a run without tasks: median force set-point while in contact. overshoot: (peak F - F_d)',
    '   / F_d, 0 if below.',
    f'impact peak F: largest F within {IMPACT_WINDOW_S:g} s of first contact.',
    f'settling time: from first contact until F stays within {SETTLING_BAND:.0%} of F_d.',
    'RMS F error: of F - F_d from settling to the release of the wall. contacts: intervals.',
    'e = X_d - X of the end effector, in contact and over the whole run.',
    f'tracking error: max |X_d - X| out of contact after t = {TRACKING_START_S:g} s.',
    'vehicle displace / rotation: largest position / attitude change from the start.',
    'current mean / max: speed of the ocean current (/uvms/ocean/current); n/a: still water.',
    'thrust scale: smallest allocator scale of the vehicle wrench (1: thrusts never saturated).',
    'n/a: does not apply (e.g. force metrics of a run without contact).',
)


def _cell(column: Column, metrics: RunMetrics, digits: int | None) -> str:
    """A value as text: fixed decimals (``digits``) or 6 significant digits (None)."""
    value = column.value(metrics)
    if value is None:
        return NOT_APPLICABLE
    if isinstance(value, str):
        return value[: column.short] if column.short and digits is not None else value
    if isinstance(value, int) and not isinstance(value, bool):
        return str(value)
    if digits is None:
        return f'{value:.6g}'
    return f'{value:.{digits}f}'


def format_report(runs: Sequence[RunMetrics], fmt: str = 'text') -> str:
    """The metrics of ``runs`` as a table, one row per run, in 'text', 'markdown' or 'csv'."""
    if fmt == 'csv':
        buffer = io.StringIO()
        writer = csv.writer(buffer, lineterminator='\n')
        writer.writerow([column.key for column in COLUMNS])
        for metrics in runs:
            writer.writerow([_cell(column, metrics, None) for column in COLUMNS])
        return buffer.getvalue()
    rows = [[_cell(column, metrics, column.digits) for column in COLUMNS] for metrics in runs]
    if fmt == 'markdown':
        headings = [
            _flat(column.label) + (f' ({column.unit})' if column.unit else '')
            for column in COLUMNS
        ]
        lines = [
            '| ' + ' | '.join(headings) + ' |',
            '| '
            + ' | '.join('---' if column.key in _LEFT_ALIGNED else '---:' for column in COLUMNS)
            + ' |',
            *('| ' + ' | '.join(cell.replace('|', '\\|') for cell in row) + ' |' for row in rows),
        ]
        return '\n'.join([*lines, '', *LEGEND]) + '\n'
    if fmt != 'text':
        raise ValueError(f'unknown report format {fmt!r}; expected one of {", ".join(FORMATS)}')
    heading_lines = max(column.label.count('\n') + 1 for column in COLUMNS)
    heading_cells = [
        [
            *([''] * (heading_lines - column.label.count('\n') - 1)),
            *column.label.split('\n'),
            f'[{column.unit}]' if column.unit else '',
        ]
        for column in COLUMNS
    ]
    widths = [
        max(*(len(text) for text in heading), *(len(row[i]) for row in rows))
        for i, heading in enumerate(heading_cells)
    ]

    def line(cells: Sequence[str]) -> str:
        aligned = (
            cell.ljust(width) if column.key in _LEFT_ALIGNED else cell.rjust(width)
            for cell, width, column in zip(cells, widths, COLUMNS, strict=True)
        )
        return '  '.join(aligned).rstrip()

    table = [
        *(line([heading[k] for heading in heading_cells]) for k in range(heading_lines + 1)),
        line(['-' * width for width in widths]),
        *(line(row) for row in rows),
    ]
    return '\n'.join([*table, '', *LEGEND]) + '\n'


def _flat(label: str) -> str:
    """A heading on one line."""
    return label.replace('-\n', '').replace('\n', ' ')


def no_task_record(path: str, run: Run) -> str:
    """What a row of a recording without a task record is, for stderr.

    A run whose recorded mission sent tasks yet holds no record lost it (a warning: the row
    is not the task's); any other run (free motion, goals sent by hand) gets a note.
    """
    sent = bool(run.metadata.get('uvms', {}).get('mission'))
    what = ('warning: the run sent contact tasks (its mission) but ' if sent else 'note: ')
    return (f'{what}{path} holds no task record ({TOPIC_TASK_RECORD}): one row for the '
            'whole recording, task n/a, F_d its median set-point while in contact')


def build_parser() -> argparse.ArgumentParser:
    """Argument parser of `uvms report`."""
    parser = argparse.ArgumentParser(
        prog='uvms report',
        description='Print the performance metrics of UVMS recordings (MCAP): one row per '
        'contact task of a recording (its goal id in column task), or one row per recording '
        'without tasks; run (the scenario name) and file (the recording) identify it.',
    )
    parser.add_argument('recordings', nargs='+', metavar='F.mcap', help='recordings to analyse')
    parser.add_argument(
        '--format', choices=FORMATS, default='text', help='table format (default: text)'
    )
    parser.add_argument(
        '--force-source',
        choices=('auto', 'contact', 'controller'),
        default='auto',
        help='force for the force metrics: simulator ground truth (contact), the '
        "controller's measured F_e (controller: a task's row then equals its result), or "
        "auto (default): ground truth when recorded, as uvms plot's figures and "
        "docs/results.md use it, else the controller's; the column 'force from' says which",
    )
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run `uvms report` with the arguments after the subcommand; returns the exit status.

    Unreadable recordings are reported on stderr and make the status 1; the table still
    lists the readable ones.
    """
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else 2
    metrics: list[RunMetrics] = []
    estimates: list[tuple[str, EstimateErrors]] = []
    failed = False
    for path in args.recordings:
        try:
            run = load_run(path)
        except AnalysisError as exc:
            print(f'uvms report: error: {exc}', file=sys.stderr)
            failed = True
            continue
        if run.problem is not None:
            print(f'uvms report: warning: {run.problem}', file=sys.stderr)
        if not run.tasks:
            print(f'uvms report: {no_task_record(path, run)}', file=sys.stderr)
        metrics.extend([task_metrics(run, task, args.force_source) for task in run.tasks]
                       or [compute_metrics(run, args.force_source)])
        errors = estimate_errors(path)
        if errors is not None:
            estimates.append((metrics[-1].name, errors))
    if metrics:
        sys.stdout.write(format_report(metrics, args.format))
    if estimates:  # runs with the estimator (state_source: estimate): its errors vs the truth
        sys.stdout.write('\nestimate (odometry/filtered) against the truth (odometry):\n')
        sys.stdout.write(format_estimate_errors(estimates))
    return 1 if failed else 0


if __name__ == '__main__':
    sys.exit(main())
