"""The controller's guards: raising callbacks are answered, the allocator's state followed."""

from __future__ import annotations

from typing import Any

from lifecycle_msgs.msg import State, TransitionEvent
from uvms_control.node_safety import AllocatorWatch, guarded

UNCONFIGURED, INACTIVE, ACTIVE = (State.PRIMARY_STATE_UNCONFIGURED,
                                  State.PRIMARY_STATE_INACTIVE, State.PRIMARY_STATE_ACTIVE)
CONFIGURING, ACTIVATING, DEACTIVATING = (State.TRANSITION_STATE_CONFIGURING,
                                         State.TRANSITION_STATE_ACTIVATING,
                                         State.TRANSITION_STATE_DEACTIVATING)
LABELS = {UNCONFIGURED: 'unconfigured', INACTIVE: 'inactive', ACTIVE: 'active',
          CONFIGURING: 'configuring', ACTIVATING: 'activating', DEACTIVATING: 'deactivating'}


class FakeNode:
    """Just what AllocatorWatch asks of a node: one subscription, its callback kept."""

    def create_subscription(self, msg_type: Any, topic: str, callback: Any, qos: Any) -> str:
        """Keep the topic and callback."""
        self.topic, self.callback = topic, callback
        return 'subscription'


def event(start: int, goal: int) -> TransitionEvent:
    """A transition event from one state to another."""
    msg = TransitionEvent()
    msg.start_state = State(id=start, label=LABELS[start])
    msg.goal_state = State(id=goal, label=LABELS[goal])
    return msg


def test_allocator_start_up_changes_nothing_and_leaving_active_stops_control() -> None:
    """Start-up transitions in any order are no news; deactivating is; active again is."""
    node, changes = FakeNode(), []
    watch = AllocatorWatch(node, 'thruster_allocator',  # type: ignore[arg-type]
                           lambda active, label: changes.append((active, label)))
    assert node.topic == 'thruster_allocator/transition_event' and watch.active
    for start, goal in ((UNCONFIGURED, CONFIGURING), (CONFIGURING, INACTIVE),
                        (INACTIVE, ACTIVATING)):
        node.callback(event(start, goal))
    assert changes == [] and watch.active
    node.callback(event(ACTIVATING, ACTIVE))
    node.callback(event(ACTIVE, DEACTIVATING))
    node.callback(event(DEACTIVATING, INACTIVE))
    assert changes == [(False, 'deactivating')] and not watch.active
    node.callback(event(INACTIVE, ACTIVATING))
    node.callback(event(ACTIVATING, ACTIVE))
    assert changes == [(False, 'deactivating'), (True, 'active')] and watch.active


class Guarded:
    """A node-like object whose callbacks are guarded."""

    def __init__(self) -> None:
        self.faults: list[tuple[str, BaseException]] = []

    def _fault(self, where: str, error: BaseException) -> str:
        self.faults.append((where, error))
        return 'answered'

    @guarded('the callback')
    def callback(self, value: int) -> int:
        """Twice the value; raises for a negative one."""
        if value < 0:
            raise RuntimeError(f'bad value {value}')
        return 2 * value


def test_guarded_callback_passes_results_and_answers_exceptions() -> None:
    """A guarded callback returns its value; an exception goes to _fault, not to the caller."""
    node = Guarded()
    assert node.callback(3) == 6
    assert node.callback(-1) == 'answered'
    ((where, error),) = node.faults
    assert where == 'the callback' and isinstance(error, RuntimeError)
