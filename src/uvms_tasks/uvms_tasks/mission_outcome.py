"""How a mission process tells its launcher what failed: an exit status and an outcome file.

Pure Python (no rclpy): ``uvms launch`` reads it without joining the graph. The mission node
(``uvms_tasks.mission_node``) exits ``EXIT_MISSION_FAILED`` when a task did not succeed, a
status no node start-up error or crash gives (those exit 1), and, when its parameter
``outcome_file`` names a file, writes there one JSON object: whether the mission succeeded,
and the first failed task's name, code (``NO_CONTACT``, ``TRACKING_LIMIT``, ``REJECTED``, ...)
and the result's message. A file rather than a parsed log line: the launcher's reading does
not depend on the log format, on colours, or on the children's output being captured.

Example::

    write_outcome(path, MissionOutcome(False, 'press', 'NO_CONTACT',
                                       'the path ended without contact'))
    read_outcome(path).line()   # 'mission failed: NO_CONTACT (the path ended without contact)'
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path

#: Latched topic (std_msgs/Bool, relative to the namespace) on which the mission says, once,
#: that it found the controller's action server; a simulator with ``startup.mission`` holds
#: its first state until then.
MISSION_READY_TOPIC = 'mission/ready'
#: Exit status of a mission process whose mission failed (a task did not succeed); 0 when
#: every task succeeded, 1 when the node could not start or crashed.
EXIT_MISSION_FAILED = 3


@dataclass(frozen=True)
class MissionOutcome:
    """The end of a mission.

    Attributes:
        succeeded: Every task SUCCEEDED.
        task: Name of the first task that did not succeed ('' if none).
        code: Its result code name (``NO_CONTACT``), ``REJECTED``, or its goal status name.
        message: The result's ``error_string`` ('' if it gave none).
    """

    succeeded: bool
    task: str = ''
    code: str = ''
    message: str = ''

    def line(self) -> str:
        """``mission failed: NO_CONTACT (the path ended without contact)``, or ``mission done``."""
        if self.succeeded:
            return 'mission done'
        detail = f' ({self.message})' if self.message else ''
        return f'mission failed: {self.code or "UNKNOWN"}{detail}'


def write_outcome(path: str | Path, outcome: MissionOutcome) -> None:
    """Write the outcome file (replaced whole: a reader never sees half of it)."""
    target = Path(path)
    partial = target.with_name(target.name + '.partial')
    partial.write_text(json.dumps(asdict(outcome)) + '\n', encoding='utf-8')
    partial.replace(target)


def read_outcome(path: str | Path) -> MissionOutcome | None:
    """The outcome written by a mission process; None if it wrote none (or not readable)."""
    try:
        values = json.loads(Path(path).read_text(encoding='utf-8'))
        return MissionOutcome(bool(values['succeeded']), str(values.get('task', '')),
                              str(values.get('code', '')), str(values.get('message', '')))
    except (OSError, ValueError, KeyError, TypeError):
        return None
