"""The flag a stopping sweep raises and its running points poll: a small Ray actor.

Ctrl-C (or SIGTERM) in the driver sets the flag; every running point task asks it at each
check of its point process and, once set, stops that process and returns. The driver
starts the actor and **waits until it has answered once** before it sends any point task:
a task whose argument is an actor that Ray has not registered yet fails as a whole when the
registration fails (``DEPENDENCY_RESOLUTION_FAILED``, e.g. a GCS timeout; ray-project/ray
#60910), which made both points of a sweep fail on a loaded machine. An actor that does not
answer is started once more; if that one fails too, the sweep runs without a flag and a stop
falls back to cancelling the tasks after the grace time.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Mapping
from typing import Any

from uvms_common.stop_event import StopEvent

from uvms_sweep.point import execute_point

#: Wall-clock limit of one task's question to the flag (s); no answer: the point goes on.
STOP_ASK_TIMEOUT_S = 5.0
#: Wall-clock limit for a new flag actor to answer its first question (s): starting its
#: worker process takes a few seconds, much longer on a loaded machine.
FLAG_START_TIMEOUT_S = 60.0
#: Flag actors tried before a sweep runs without one.
FLAG_ATTEMPTS = 2
#: Wall-clock period at which the wait for the flag checks for Ctrl-C (s).
_POLL_S = 0.5

_LOG = logging.getLogger(__name__)


class StopFlag:
    """A flag the driver sets on Ctrl-C and the running point tasks poll (a Ray actor)."""

    def __init__(self) -> None:
        """Not set."""
        self._set = False

    def set(self) -> None:
        """Ask every running point to stop."""
        self._set = True

    def is_set(self) -> bool:
        """Whether the sweep is stopping."""
        return self._set


def point_task(
    request: Mapping[str, Any], domain_id: int, timeout_s: float, stop_flag: Any | None
) -> dict[str, Any]:
    """The Ray task of one point: ``execute_point``, stopped when ``stop_flag`` is set.

    ``stop_flag`` None (no flag could be started): the point runs to its end or timeout.
    """
    if stop_flag is None:
        return execute_point(request, domain_id, timeout_s, should_stop=lambda: False)
    import ray

    def should_stop() -> bool:
        try:
            return bool(ray.get(stop_flag.is_set.remote(), timeout=STOP_ASK_TIMEOUT_S))
        except (ray.exceptions.GetTimeoutError, ray.exceptions.RayActorError):
            return False

    return execute_point(request, domain_id, timeout_s, should_stop=should_stop)


def ray_error_line(exc: BaseException) -> str:
    """``Type: first line of the message`` of an error Ray raised (its messages run long)."""
    text = str(exc).strip()
    return f'{type(exc).__name__}: {text.splitlines()[0] if text else ""}'


def start_stop_flag(
    ray: Any, stop: StopEvent | None, *, timeout_s: float = FLAG_START_TIMEOUT_S
) -> Any | None:
    """A StopFlag actor that has answered once, or None when none would start.

    Args:
        ray: The ray module, connected.
        stop: The driver's Ctrl-C event: a set event ends the wait (None is returned).
        timeout_s: Wall time each attempt waits for the first answer.
    """
    for attempt in range(1, FLAG_ATTEMPTS + 1):
        flag = ray.remote(num_cpus=0)(StopFlag).remote()
        reason = _first_answer(ray, flag, stop, timeout_s)
        if reason is None:
            return flag
        ray.kill(flag)
        if stop is not None and stop.is_set():
            return None
        _LOG.warning('the sweep stop flag (attempt %d of %d) %s', attempt, FLAG_ATTEMPTS, reason)
    _LOG.warning('running without a stop flag: Ctrl-C cancels the points after the grace time')
    return None


def _first_answer(ray: Any, flag: Any, stop: StopEvent | None, timeout_s: float) -> str | None:
    """None once ``flag`` answered; otherwise why not (Ray's error, a timeout or a stop)."""
    answer = flag.is_set.remote()
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if stop is not None and stop.is_set():
            return 'was not awaited: the sweep is stopping'
        try:
            ray.get(answer, timeout=_POLL_S)
        except ray.exceptions.GetTimeoutError:
            continue
        except ray.exceptions.RayError as exc:
            return f'failed: {ray_error_line(exc)}'
        return None
    return f'did not answer within {timeout_s:g} s'
