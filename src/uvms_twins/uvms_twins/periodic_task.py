"""When a periodic task of an autopilot's scheduler runs next, as ArduPilot's AP_Scheduler does.

AP_Scheduler (``libraries/AP_Scheduler/AP_Scheduler.cpp``, ``run``) records the tick at which
a task ran (``_last_run[i] = _tick_counter``) and runs it again once ``interval_ticks`` have
passed since then: a task that ran late runs once, not once for every interval it missed.
The ArduSub twin's 50 Hz RC read follows it (issue 48: a twin thread that got no CPU for a
while used to catch up with reads back to back).
"""

from __future__ import annotations


def next_run_s(due_s: float, ran_s: float, period_s: float) -> float:
    """When a task due at ``due_s`` that ran at ``ran_s`` is due again (s).

    Less than a period late (the twin's own polling, which the autopilot's fixed-rate ticks
    do not have) it keeps its grid; later than that it is due one period after it ran, the
    missed runs left out, as AP_Scheduler does.
    """
    following = due_s + period_s
    return following if following > ran_s else ran_s + period_s
