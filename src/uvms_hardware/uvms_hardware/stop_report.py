"""What each bridge put back at its stop, said on the console and handed to ``uvms launch``.

A bridge's put-back (``bridge_node``'s ``put_device_back``) ends with one console line,
``put back: thrusters neutral, disarmed, ...``, and, when ``uvms launch`` started it (the
environment names a folder, `ENV`), the same words in ``<node>.json`` there, so that the
launch's last line can say what every bridge put back, and which said nothing (a kill)::

    write_stop_report('ardusub_bridge', 'thrusters neutral, disarmed', problems=[])
    line = stop_summary(read_stop_reports(folder), ['ardusub_bridge', 'alpha5_bridge'])

No ROS; a report that cannot be written is not a problem of the device (the console line
stands).
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from pathlib import Path

#: Environment variable naming the folder of the stop reports (set by ``uvms launch``).
ENV = 'UVMS_STOP_REPORT_DIR'


def write_stop_report(node: str, done: str, problems: Sequence[str]) -> None:
    """``node``'s put-back for the launcher: what was done and what could not be (if asked)."""
    folder = os.environ.get(ENV, '')
    if not folder:
        return
    try:
        (Path(folder) / f'{node}.json').write_text(
            json.dumps({'done': done, 'problems': list(problems)}), encoding='utf-8')
    except OSError:
        pass  # the console line already said it


def read_stop_reports(folder: str | Path) -> dict[str, dict[str, object]]:
    """Every report in ``folder``: node -> {'done': str, 'problems': [str]}."""
    reports = {}
    for path in sorted(Path(folder).glob('*.json')):
        try:
            reports[path.stem] = json.loads(path.read_text(encoding='utf-8'))
        except (OSError, ValueError):
            continue
    return reports


def stop_summary(reports: Mapping[str, Mapping[str, object]], bridges: Sequence[str]) -> str:
    """``put back: ardusub_bridge: ...; alpha5_bridge: ...``, each bridge of ``bridges`` named.

    A bridge with problems says how many (its log names them); one without a report did not
    get to its put-back (killed, or it never activated).
    """
    parts = []
    for bridge in bridges:
        report = reports.get(bridge)
        if report is None:
            parts.append(f'{bridge}: no put-back reported (never active, or killed: '
                         'uvms hardware check)')
            continue
        problems = report.get('problems') or []
        count = len(problems) if isinstance(problems, list) else 0
        parts.append(f'{bridge}: {report.get("done", "?")}'
                     + (f' ({count} PROBLEM{"S" if count > 1 else ""}: see its log)'
                        if count else ''))
    return 'put back: ' + '; '.join(parts)
