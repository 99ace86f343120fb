"""The simulator's /diagnostics status from its figures: finished, holding, waiting, behind."""

from __future__ import annotations

from typing import Any

from uvms_common.diagnostics import OK, WARN, Report

#: Share of its ``real_time_factor`` below which a real-time simulation reports that it falls
#: behind.
BEHIND_REAL_TIME_FACTOR = 0.9


def simulator_report(values: dict[str, Any], *, finished: bool, holding_for: str | None,
                     first_command: bool, new_timeouts: float | None,
                     asked_factor: float) -> Report:
    """The status line for ``values`` (mode, sim_time_s, real_time_factor, ...).

    Args:
        values: The figures published with it; ``mode`` and ``real_time_factor`` are read.
        finished: ``duration_s`` reached.
        holding_for: What the held initial state waits for; None once physics runs.
        first_command: Whether an actuator command has arrived.
        new_timeouts: Lockstep timeouts per second of late, None before two samples.
        asked_factor: The ``real_time_factor`` asked for.
    """
    mode, factor = values['mode'], values['real_time_factor']
    if finished:
        return Report(OK, f'finished at t = {values["sim_time_s"]:.3f} s', values)
    if holding_for is not None:
        return Report(WARN, f'holding the initial state: waiting for {holding_for}', values)
    if mode == 'lockstep' and not first_command:
        return Report(WARN, 'waiting for the first actuator command', values)
    if mode == 'lockstep' and new_timeouts:
        return Report(WARN, 'lockstep timeouts: stepping on the last command', values)
    if mode != 'lockstep' and factor is not None and factor < (
            BEHIND_REAL_TIME_FACTOR * asked_factor):
        return Report(WARN, f'behind real time (factor {factor:.2f})', values)
    return Report(OK, 'running', values)
