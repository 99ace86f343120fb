"""The pilot's cancel key while the task's acceptance is still on its way: sent once accepted.

Seen in CI under load: key t sent the goal, the controller already ran the task, and key c
came before the pilot had the goal's acceptance; the pilot then said 'press c again' and
cancelled nothing. A cancel asked then is now kept and sent with the acceptance.
"""

from __future__ import annotations

from collections.abc import Iterator
from concurrent.futures import Future
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest
import rclpy
from rclpy.context import Context
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions
from uvms_pilot.link import PilotLink


class FakeTasks:
    """The task client's calls the link makes, answered by the test."""

    def __init__(self) -> None:
        self.goal_future: Future[Any] = Future()
        self.cancelled: list[Any] = []

    def send_goal_async(self, goal: Any, feedback: Any) -> Future[Any]:
        """The goal's acceptance, set by the test."""
        return self.goal_future

    def result_async(self, handle: Any) -> Future[Any]:
        """A result that never comes."""
        return Future()

    def cancel_async(self, handle: Any) -> None:
        """Keep the handle cancelled."""
        self.cancelled.append(handle)

    latest_state = None
    action_name = '/uvms/contact_task'

    def server_is_ready(self) -> bool:
        """The server is there."""
        return True


#: A two-waypoint task without force (map_ned).
TASK = """\
name: arc
path: [[0.0, 0.0, 0.0], [0.05, 0.0, 0.0]]
time_from_start_s: [0.0, 5.0]
normal: [1.0, 0.0, 0.0]
force_n: 0.0
require_contact: false
"""


@pytest.fixture
def link(tmp_path: Path) -> Iterator[tuple[PilotLink, FakeTasks]]:
    """A pilot link on a node of its own context with a task file, its task client faked."""
    context = Context()
    rclpy.init(args=[], context=context, signal_handler_options=SignalHandlerOptions.NO)
    node = Node('pilot_link_test', context=context)
    (tmp_path / 'task.yaml').write_text(TASK)
    pilot = PilotLink(node, 'base_link_frd', task_file=tmp_path / 'task.yaml')
    tasks = FakeTasks()
    pilot._tasks = tasks  # type: ignore[assignment]
    yield pilot, tasks
    node.destroy_node()
    rclpy.try_shutdown(context=context)


def accepted_handle() -> Any:
    """A goal handle as rclpy's, accepted."""
    return SimpleNamespace(accepted=True, cancel_goal_async=lambda: None, status=2)


def test_a_cancel_before_the_acceptance_is_sent_with_it(
        link: tuple[PilotLink, FakeTasks]) -> None:
    """Key c while the goal is on its way: 'cancel: asked', the cancel sent on acceptance."""
    pilot, tasks = link
    pilot.start_task()
    pilot.cancel_task()
    assert 'cancel: asked' in (pilot.live.note or '')
    assert tasks.cancelled == []
    handle = accepted_handle()
    tasks.goal_future.set_result(handle)
    assert tasks.cancelled == [handle]


def test_a_cancel_after_the_acceptance_goes_at_once(link: tuple[PilotLink, FakeTasks]) -> None:
    """Key c once accepted: the cancel goes out then, once."""
    pilot, tasks = link
    pilot.start_task()
    handle = accepted_handle()
    tasks.goal_future.set_result(handle)
    pilot.cancel_task()
    assert tasks.cancelled == [handle]
    assert pilot.live.note == 'cancel: asked'
