"""The table of a sweep (DIR/points.csv): one row per point, rewritten whole after each point.

Columns: ``point_id``, one per axis (its dotted name), ``seed``, ``status`` (``done`` or
``failed``), ``reason`` (why it failed: ``timeout`` or the run's error line; for a done
point why its force metrics mean little: ``ended before settling``, see ``ended_early``),
``stable`` (``yes``, ``no`` or empty, see ``stability``; empty where the run ended early),
``wall_time_s`` (the point's process, start-up included), ``sim_time_s``, ``finished_utc``,
then every metric of ``uvms report --format csv`` (empty where n/a). Values are written with
full precision (``repr``); list values as JSON.

The file is replaced atomically (write to a temporary file, then rename), so an interrupted
sweep leaves the table of the points finished before it, never half a row.
"""

from __future__ import annotations

import csv
import json
import math
import os
import tempfile
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

from uvms_sweep.sweep_file import METRIC_KEYS, Sweep

TABLE_NAME = 'points.csv'
FIXED_COLUMNS = ('status', 'reason', 'stable', 'wall_time_s', 'sim_time_s', 'finished_utc')
#: Contact intervals from which a run counts as bouncing off the wall (unstable).
UNSTABLE_CONTACTS = 2
#: Peak force over F_d above which the contact force counts as surging (unstable).
SURGE_RATIO = 2.0
#: Reason of a done point whose run ended in its only contact before the force settled.
ENDED_BEFORE_SETTLING = 'ended before settling'
#: Gap between the end of the last contact and the run's end within which the run ends in
#: contact (s): the recorder's last samples may trail the simulated end by a few periods.
END_IN_CONTACT_SLACK_S = 0.1


class TableError(RuntimeError):
    """DIR/points.csv cannot be read, or belongs to a sweep over other axes."""


def columns(sweep: Sweep) -> list[str]:
    """Column names of a sweep's table, in order."""
    return ['point_id', *(axis.name for axis in sweep.axes), 'seed', *FIXED_COLUMNS,
            *METRIC_KEYS]


def stability(metrics: Mapping[str, float | None]) -> str:
    """``no`` if the contact is not held steadily, ``yes`` if it is, empty without contact.

    Unstable: the end effector bounced (``UNSTABLE_CONTACTS`` or more contact intervals:
    it lost the wall and hit it again), or the force surged past ``SURGE_RATIO`` F_d (an
    oscillation that grows instead of settling). A force that stays below F_d without
    settling (too soft a wall for the hand-over) is stable but shows no settling time.
    """
    contacts = metrics.get('contact_count') or 0.0
    if contacts <= 0.0:
        return ''
    if contacts >= UNSTABLE_CONTACTS:
        return 'no'
    desired = metrics.get('desired_force_N')
    peak = metrics.get('peak_force_N')
    if desired and peak is not None and peak > SURGE_RATIO * desired:
        return 'no'
    return 'yes'


def ended_early(metrics: Mapping[str, float | None], sim_time_s: float | None) -> str:
    """``ENDED_BEFORE_SETTLING`` if the run ended too early for its force metrics, else ''.

    Too early: the run ends in its only contact interval and the force has no settling time,
    as a run does that stops during the force ramp after the first contact (F_d still
    rising) or before the force settled at F_d. Its desired force (the median F_d in
    contact), overshoot and settling time describe that transient, not the controller, so
    the point is marked with this reason instead of a ``stability`` verdict. A run that
    leaves the wall before its end without settling (a wall too soft for F_d) is judged.

    Example:
        >>> ended_early({'contact_count': 1.0, 'first_contact_s': 8.05,
        ...              'contact_duration_s': 0.95, 'settling_time_s': None}, 9.0)
        'ended before settling'
    """
    first = metrics.get('first_contact_s')
    duration = metrics.get('contact_duration_s')
    if (metrics.get('contact_count') != 1.0 or metrics.get('settling_time_s') is not None
            or first is None or duration is None or sim_time_s is None):
        return ''
    ends_in_contact = first + duration >= sim_time_s - END_IN_CONTACT_SLACK_S
    return ENDED_BEFORE_SETTLING if ends_in_contact else ''


def read_table(directory: Path, sweep: Sweep) -> dict[str, dict[str, str]]:
    """Rows of an existing table by point id (empty if there is none).

    Raises:
        TableError: The table's columns are not this sweep's (another sweep's directory).
    """
    path = directory / TABLE_NAME
    if not path.is_file():
        return {}
    try:
        with path.open(newline='', encoding='utf-8') as file:
            reader = csv.DictReader(file)
            header = list(reader.fieldnames or [])
            rows = [row for row in reader if row.get('point_id')]
        for row in rows:  # derived, so that a table of an older definition is brought up to date
            if row.get('status') == 'done':
                metrics = {key: metric_value(row, key) for key in METRIC_KEYS}
                row['reason'] = ended_early(metrics, metric_value(row, 'sim_time_s'))
                row['stable'] = '' if row['reason'] else stability(metrics)
    except (OSError, csv.Error) as exc:
        raise TableError(f'{path}: cannot read the sweep table: {exc}') from exc
    if header != columns(sweep):
        axes = [name for name in header if '.' in name]
        msg = (f'{path} holds a sweep over {", ".join(axes) or "other columns"}, not '
               f'{", ".join(axis.name for axis in sweep.axes)}: use another --out directory')
        raise TableError(msg)
    return {row['point_id']: row for row in rows}


def outcome_row(
    sweep: Sweep, values: Mapping[str, Any], seed: int, outcome: Mapping[str, Any],
    finished_utc: str,
) -> dict[str, str]:
    """The table row of a finished point."""
    metrics = outcome.get('metrics') or {}
    reason, stable = _one_line(outcome.get('reason', '')), ''
    if outcome['status'] == 'done':
        reason = ended_early(metrics, outcome.get('sim_time_s'))
        stable = '' if reason else stability(metrics)
    row = {'point_id': outcome['point_id'], 'seed': str(seed), 'status': outcome['status'],
           'reason': reason, 'stable': stable,
           'wall_time_s': _cell(outcome.get('wall_time_s')),
           'sim_time_s': _cell(outcome.get('sim_time_s')), 'finished_utc': finished_utc}
    for axis in sweep.axes:
        row[axis.name] = _cell(values[axis.name])
    for key in METRIC_KEYS:
        row[key] = _cell(metrics.get(key))
    return row


def write_table(directory: Path, sweep: Sweep, rows: Iterable[Mapping[str, str]]) -> Path:
    """Replace DIR/points.csv with ``rows`` atomically; returns its path."""
    path = directory / TABLE_NAME
    handle, temporary = tempfile.mkstemp(prefix='.points-', suffix='.csv', dir=directory)
    try:
        with os.fdopen(handle, 'w', newline='', encoding='utf-8') as file:
            writer = csv.DictWriter(file, fieldnames=columns(sweep), lineterminator='\n')
            writer.writeheader()
            for row in rows:
                writer.writerow(row)
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise
    return path


def metric_value(row: Mapping[str, str], key: str) -> float | None:
    """A metric of a row as a float, None where empty (n/a) or not a number."""
    text = row.get(key, '')
    if not text:
        return None
    try:
        value = float(text)
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def _cell(value: Any) -> str:
    """A value as its CSV text: repr for floats, JSON for lists, empty for None."""
    if value is None:
        return ''
    if isinstance(value, bool):
        return 'true' if value else 'false'
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, Sequence) and not isinstance(value, str):
        return json.dumps(list(value))
    return str(value)


def _one_line(text: str) -> str:
    """A reason on one line (a CSV cell that reads well in a spreadsheet)."""
    return ' '.join(text.split())
