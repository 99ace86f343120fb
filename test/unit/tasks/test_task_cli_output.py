"""``uvms task`` on a terminal: each result printed after Ctrl-C starts on a line of its own."""

from __future__ import annotations

import io
from collections.abc import Callable
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest
from uvms_common.stop_event import StopEvent
from uvms_tasks.task_file import load_task_file

from uvms_msgs.action import ContactTask
from uvms_tasks import cli

TASKS = Path(__file__).resolve().parents[3] / 'config' / 'tasks'


class Terminal(io.StringIO):
    """stdout and stderr of one terminal: both streams write into one text, in order."""

    def isatty(self) -> bool:
        """A terminal, so that the progress line is drawn."""
        return True


class _Done:
    """A future that is done when ``flag()`` says so."""

    def __init__(self, value: Any, flag: Callable[[], bool] = lambda: True) -> None:
        self._value = value
        self._flag = flag

    def done(self) -> bool:
        return self._flag()

    def result(self) -> Any:
        return self._value


class FakeClient:
    """A ContactTaskClient stand-in: feedback flows until Ctrl-C, then the cancel's result.

    Every spin delivers one feedback; the first spin waiting for the result is interrupted
    (the stop event is set, as SIGINT does); the cancel then ends the goal CANCELED after
    one more feedback, as the controller's retreat does.
    """

    action_name = '/uvms/controller/contact_task'
    latest_state = None

    def __init__(self, stop: StopEvent) -> None:
        self.stop = stop
        self.feedback: Callable[[Any], None] = lambda _: None
        self.canceled = False

    def send_goal_async(self, goal: Any, feedback: Callable[[Any], None]) -> _Done:
        """Accept the goal at once."""
        self.feedback = feedback
        return _Done(SimpleNamespace(accepted=True, status=2))

    def result_async(self, handle: Any) -> _Done:
        """The result: CANCELED (status 5), once the goal was canceled."""
        result = ContactTask.Result(error_code=ContactTask.Result.CANCELED)
        response = SimpleNamespace(status=5, result=result)
        return _Done(response, lambda: self.canceled)

    def cancel_async(self, handle: Any) -> None:
        """Cancel: the result comes after the next feedback."""
        self.canceled = True

    def spin_until(self, done: Callable[[], bool], timeout_s: float | None) -> bool:
        """One feedback; then Ctrl-C if the awaited thing is not done."""
        feedback = ContactTask.Feedback(state=2, phase=2, weight=0.5, force_n=140.0,
                                        force_desired_n=150.0, progress=0.986)
        self.feedback(feedback)
        if not done():
            self.stop.set()
        return done()


def test_result_after_ctrl_c_starts_on_its_own_line(monkeypatch: pytest.MonkeyPatch) -> None:
    """The CANCELED result is not glued onto the progress line the cancel redrew."""
    terminal = Terminal()
    monkeypatch.setattr(cli.sys, 'stdout', terminal)
    monkeypatch.setattr(cli.sys, 'stderr', terminal)
    monkeypatch.setattr(cli, 'PROGRESS_INTERVAL_S', 0.0)
    stop = StopEvent()
    try:
        task = load_task_file(TASKS / 'press_100n.yaml')[0]
        run = cli._TaskRun(FakeClient(stop), stop, timeout_s=1.0)  # type: ignore[arg-type]
        assert run.run_task(task) is None
    finally:
        stop.restore()
    text = terminal.getvalue()
    result = f'{task.name}: CANCELED'
    assert result in text
    before = text[:text.index(result)]
    assert '98.6 %' in before, 'the cancel redraws the progress line: the case under test'
    assert before.endswith('\n')
