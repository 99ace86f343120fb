"""What a node process tells its launcher through files: first step, periods, lateness.

``uvms launch`` sets ``UVMS_STATS_DIR`` for its children; a node process then writes small
JSON files there (nothing without it, as under ``ros2 run``): the simulator
``first_step.json`` when physics starts (``CLOCK_MONOTONIC`` ns, one clock for every process
of the machine), and every process ``<name>.json`` as it ends, with the periods its
``MissCounter`` objects counted (``uvms_common.realtime``). Files, not topics: the launcher
has no rclpy, and a node's last figures arrive after its last message could.
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path
from typing import Any

#: Environment variable naming the directory (set by ``uvms launch`` for its children).
ENV = 'UVMS_STATS_DIR'
#: File of the simulator's first physics step.
FIRST_STEP = 'first_step'
#: File of a run's end reached by a simulator that keeps serving until it is stopped (the
#: protocol twins in its process: the bridges put their devices back through them first).
END_REACHED = 'end_reached'


def stats_dir() -> Path | None:
    """The directory of this process's stats files, None when no launcher asked for them."""
    value = os.environ.get(ENV)
    return Path(value) if value else None


def write(name: str, values: dict[str, Any]) -> None:
    """Write ``<name>.json`` into the stats directory (atomically), if there is one."""
    directory = stats_dir()
    if directory is None:
        return
    try:
        directory.mkdir(parents=True, exist_ok=True)
        partial = directory / f'.{name}.{os.getpid()}.tmp'
        partial.write_text(json.dumps(values), encoding='utf-8')
        partial.replace(directory / f'{name}.json')
    except OSError:
        pass  # figures for the launcher's summary only: never a reason to fail a node


def mark_first_step() -> None:
    """The simulator's first physics step: now, on CLOCK_MONOTONIC (ns)."""
    write(FIRST_STEP, {'monotonic_ns': time.monotonic_ns(), 'pid': os.getpid()})


def mark_end_reached() -> bool:
    """The run's end reached (the launcher's cue to stop the graph); False without a launcher."""
    if stats_dir() is None:
        return False
    write(END_REACHED, {'monotonic_ns': time.monotonic_ns(), 'pid': os.getpid()})
    return True


def read(directory: Path, name: str) -> dict[str, Any] | None:
    """``<name>.json`` of a stats directory, None while it does not exist or is unreadable."""
    try:
        data = json.loads((directory / f'{name}.json').read_text(encoding='utf-8'))
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None
