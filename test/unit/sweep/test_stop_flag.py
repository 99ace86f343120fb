"""The sweep's stop flag is answering before any point depends on it, or there is none.

Ray itself is replaced by a stand-in of the four calls ``start_stop_flag`` makes (``remote``,
``get``, ``kill`` and the exception classes): a failed actor registration (a GCS timeout on
a loaded machine) cannot be caused on purpose with a real Ray.
"""

from __future__ import annotations

import threading
import time
from types import SimpleNamespace
from typing import Any

from uvms_common.stop_event import StopEvent
from uvms_sweep.stop_flag import StopFlag, start_stop_flag

from uvms_sweep import stop_flag as flag_module


class StandInRayError(Exception):
    """ray.exceptions.RayError."""


class StandInTimeoutError(StandInRayError):
    """ray.exceptions.GetTimeoutError."""


class Actor:
    """One started flag: answers, fails (Ray's error) or stays silent."""

    def __init__(self, behaviour: str) -> None:
        self.behaviour = behaviour
        self.killed = False
        self.is_set = SimpleNamespace(remote=lambda: self)


class StandInRay:
    """The Ray calls of ``start_stop_flag``: actors behave as ``behaviours`` says, in turn."""

    exceptions = SimpleNamespace(RayError=StandInRayError, GetTimeoutError=StandInTimeoutError)

    def __init__(self, *behaviours: str) -> None:
        self.behaviours = list(behaviours)
        self.actors: list[Actor] = []

    def remote(self, **options: Any) -> Any:
        """``ray.remote(num_cpus=0)(StopFlag)``: an actor class whose ``remote`` starts one."""
        assert options == {'num_cpus': 0}
        return lambda cls: SimpleNamespace(remote=self._start) if cls is StopFlag else None

    def _start(self) -> Actor:
        self.actors.append(Actor(self.behaviours.pop(0)))
        return self.actors[-1]

    def get(self, answer: Actor, timeout: float) -> bool:
        """``ray.get`` of an ``is_set`` answer."""
        if answer.behaviour == 'fails':
            raise StandInRayError('ActorDiedError: the actor could not be registered\nmore')
        if answer.behaviour == 'silent':
            time.sleep(timeout)
            raise StandInTimeoutError
        return False

    def kill(self, actor: Actor) -> None:
        """``ray.kill``."""
        actor.killed = True


def test_a_flag_that_answers_is_used(caplog: Any) -> None:
    """The usual case: the first flag answers, is kept, and nothing is logged."""
    ray = StandInRay('answers')
    flag = start_stop_flag(ray, None)
    assert flag is ray.actors[0] and not flag.killed
    assert caplog.text == ''


def test_a_flag_whose_registration_failed_is_replaced_by_one_that_answers(caplog: Any) -> None:
    """The failure that made every point of a sweep fail with DEPENDENCY_RESOLUTION_FAILED."""
    ray = StandInRay('fails', 'answers')
    flag = start_stop_flag(ray, None)
    assert flag is ray.actors[1]
    assert ray.actors[0].killed
    assert 'attempt 1 of 2' in caplog.text and 'could not be registered' in caplog.text


def test_without_any_answering_flag_the_sweep_runs_without_one(caplog: Any) -> None:
    """Two flags that fail or stay silent: None, both killed, and the user is told."""
    ray = StandInRay('fails', 'silent')
    assert start_stop_flag(ray, None, timeout_s=1.0) is None
    assert all(actor.killed for actor in ray.actors)
    assert 'did not answer within 1 s' in caplog.text
    assert 'running without a stop flag' in caplog.text


def test_ctrl_c_ends_the_wait_for_a_silent_flag_at_once() -> None:
    """Ctrl-C during the wait: no second flag, no 30 s wait."""
    ray = StandInRay('silent', 'answers')
    stop = StopEvent()
    threading.Timer(0.3, stop.set).start()
    started = time.monotonic()
    assert start_stop_flag(ray, stop, timeout_s=30.0) is None
    assert time.monotonic() - started < 5.0
    assert len(ray.actors) == 1 and ray.actors[0].killed


def test_a_point_without_a_flag_is_never_asked_to_stop(monkeypatch: Any) -> None:
    """A point task given no flag runs its point with a stop check that says no."""
    seen: dict[str, Any] = {}

    def execute_point(request: Any, domain_id: int, timeout_s: float, *, should_stop: Any) -> Any:
        seen['stop'] = should_stop()
        return {'status': 'done'}

    monkeypatch.setattr(flag_module, 'execute_point', execute_point)
    assert flag_module.point_task({}, 215, 10.0, None) == {'status': 'done'}
    assert seen == {'stop': False}
