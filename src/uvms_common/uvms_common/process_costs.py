"""What a launch's processes cost, as ``uvms launch`` prints it: first step, CPU, periods.

The launcher has no rclpy: it reads the kernel's accounting of its children
(``/proc/PID/stat`` utime + stime, every thread of the process) and the files the node
processes write into ``UVMS_STATS_DIR`` (``uvms_common.process_stats``): the simulator's
first physics step, and each process's periods, missed periods and worst lateness at its
end. CPU is counted from the first simulated step to the end of the run, so the start-up
(imports, model and kernel loading) is not in it.
"""

from __future__ import annotations

import os
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from uvms_common import process_stats

#: Clock ticks per second of /proc/PID/stat's utime and stime.
_TICKS_S = os.sysconf('SC_CLK_TCK')


def cpu_seconds(pid: int) -> float | None:
    """User + system CPU of a process so far (s), None once it is gone."""
    try:
        fields = Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()
    except OSError:
        return None
    # Fields 14 and 15 of proc(5) (utime, stime); fields[0] here is field 3 (state).
    return (int(fields[11]) + int(fields[12])) / _TICKS_S


@dataclass
class CostWatch:
    """Watches a launch: the first simulated step, then CPU per process until the end.

    Attributes:
        directory: The children's ``UVMS_STATS_DIR``.
        started_ns: CLOCK_MONOTONIC when the launch started its first process (ns).
        first_step_s: Seconds from the start to the first simulated step, once seen.
    """

    directory: Path
    started_ns: int = field(default_factory=time.monotonic_ns)
    first_step_s: float | None = None
    #: Per pid: (monotonic s, CPU s) at the first step and at the latest sample.
    _first: dict[int, tuple[float, float]] = field(default_factory=dict)
    _last: dict[int, tuple[float, float]] = field(default_factory=dict)

    def poll(self, pids: Sequence[int]) -> str | None:
        """Sample CPU (after the first step); the first-step line once it is seen, else None.

        Sampled at every poll, so a process that ends by itself (the simulator at its
        duration) keeps its figure up to its last poll.
        """
        if self.first_step_s is not None:
            self._sample(pids, self._last)
            return None
        mark = process_stats.read(self.directory, process_stats.FIRST_STEP)
        if mark is None:
            return None
        self.first_step_s = (int(mark['monotonic_ns']) - self.started_ns) * 1e-9
        self._sample(pids, self._first)
        return (f'uvms launch: first simulated step {self.first_step_s:.2f} s after the '
                'launch started')

    def end(self, pids: Sequence[int]) -> None:
        """The run is over (before the processes are stopped): the last CPU sample."""
        if self.first_step_s is not None:
            self._sample(pids, self._last)

    @staticmethod
    def _sample(pids: Sequence[int], into: dict[int, tuple[float, float]]) -> None:
        now = time.monotonic()
        for pid in pids:
            cpu = cpu_seconds(pid)
            if cpu is not None:
                into[pid] = (now, cpu)

    def window_s(self) -> float:
        """Wall seconds from the first step to the last sample."""
        if not self._first or not self._last:
            return 0.0
        return max(t for t, _ in self._last.values()) - min(t for t, _ in self._first.values())

    def cpu_percent(self, pid: int) -> float | None:
        """CPU of a process in % of one core from the first step to its last sample."""
        if pid not in self._first or pid not in self._last:
            return None
        (t0, cpu0), (t1, cpu1) = self._first[pid], self._last[pid]
        return 100.0 * (cpu1 - cpu0) / (t1 - t0) if t1 > t0 else None

    def table(self, processes: Sequence[tuple[str, int]]) -> list[str]:
        """Lines of the closing table: per process (name, pid) CPU, missed periods, lateness."""
        rows = []
        total = 0.0
        for name, pid in processes:
            cpu = self.cpu_percent(pid)
            total += cpu or 0.0
            stats = process_stats.read(self.directory, name) or {}
            periods, missed = stats.get('periods') or 0, stats.get('missed') or 0
            late = stats.get('worst_late_ms')
            rows.append(f'  {name:<19} {_cell(cpu, "{:5.1f} %"):>8}  '
                        f'{_missed(periods, missed):>22}  {_cell(late, "{:.1f} ms"):>9}')
        header = (f'  {"process":<19} {"CPU":>8}  {"missed periods":>22}  {"worst late":>9}')
        return [f'uvms launch: cost per process over {self.window_s():.1f} s from the first step '
                '(CPU in % of one core):', header, *rows,
                f'  {"graph":<19} {total:6.1f} %']


def _cell(value: float | None, form: str) -> str:
    return '-' if value is None else form.format(value)


def _missed(periods: int, missed: int) -> str:
    if not periods:
        return '-'
    return f'{missed} of {periods} ({100.0 * missed / periods:.2f} %)'
