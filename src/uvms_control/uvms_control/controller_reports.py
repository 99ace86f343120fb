"""The controller node's /diagnostics reports: control (rates, inputs, faults) and task.

A mixin of ``ControllerNode`` (as ``controller_safety`` is): the two reports read the node's
counters, inputs, allocator watch, fault log and task supervisor, and change nothing.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from uvms_common.diagnostics import ERROR, OK, WARN, Report
from uvms_common.diagnostics import robot_name as urdf_robot_name
from uvms_common.lifecycle import state_label

from uvms_model import ModelError, UvmsParameters


class ControllerReports:
    """``_report_control`` and ``_report_task`` of the controller node (mixin)."""

    _robot: Any
    _rate: Any
    _counts: Any
    _inputs: Any
    _stale: Any
    _staleness: Any
    _misses: Any
    _allocator: Any
    _faults: Any
    _breach: Any
    supervisor: Any
    tasks: Any

    def _hardware_id(self) -> str:
        """The robot's name from its URDF, for the reports' hardware_id."""
        try:
            urdf = UvmsParameters.from_flat_dict(self._robot).description.urdf_path
            return urdf_robot_name(Path(urdf).read_text())
        except (ModelError, OSError):
            return urdf_robot_name(None)

    def _report_control(self) -> Report:
        """Lifecycle state, rate, input ages, rejections, faults and the allocator."""
        state = state_label(self)
        now = self.get_clock().now().nanoseconds
        rate = self._rate.rate_hz(self._counts['steps'], now)
        ages = {f'{topic}_age_s': (now - value.arrival_ns) * 1e-9 if value and value.arrival_ns
                else None for topic, value in self._inputs.items()}
        stale = self._stale or self._staleness.alarmed
        misses = self._misses
        level = OK if state == 'active' and not stale else WARN
        message = 'stale inputs: zero command' if stale else state
        if not stale and self._staleness.stale:
            message = f'{state}: waiting for fresh inputs (start-up)'
        allocator = self._allocator
        if allocator is not None and not allocator.active:
            level, message = WARN, f'thruster allocator {allocator.label}: zero command'
        if self._faults.recent:
            level, message = ERROR, f'survived a fault: {self._faults.last}'
        return Report(level, message, {'lifecycle_state': state, 'rate_hz': rate,
                                       'allocator': allocator.label if allocator
                                       else 'not watched',
                                       **self._faults.values(),
                                       'rejected_inputs': self._counts['rejected'],
                                       'malformed_inputs': self._counts['malformed'],
                                       'zero_commands': self._counts['zeroed'],
                                       'missed_periods': misses.missed if misses else None,
                                       'missed_share': misses.share if misses else None,
                                       **ages})

    def _report_task(self) -> Report:
        """The running task, its progress and the last safety limit reached."""
        supervisor = self.supervisor
        progress = supervisor.progress() if supervisor is not None else None
        last = supervisor.last_result if supervisor is not None else None
        values = {'task': 'none' if progress is None else progress.state.name.lower(),
                  'progress': None if progress is None else progress.progress,
                  'phase': None if last is None else last.phase.name.lower(),
                  'weight': None if last is None else last.W,
                  'goals_received': self.tasks.goals_received,
                  'last_result': self.tasks.last_outcome}
        if self._breach is not None:
            clear = (f'; clear it: uvms lifecycle {self.get_name()} reset'
                     if supervisor is not None and supervisor.safe_hold else '')
            return Report(ERROR, f'safety limit: {self._breach}{clear}', values)
        return Report(OK, 'holding' if progress is None else 'running a contact task', values)
