"""Start-up of the control loop: physics holds the initial state until control answers (pure).

The simulator publishes the initial state at t_0 and holds it (simulated time does not
advance) until the loop is closed, so that the plant never integrates commands of nodes that
are still loading. Time stands still rather than the state alone: the controller's and the
simulator's watchdogs measure command age in simulated time, and the mission's goals are
stamped on ``/clock`` (``start_time_s``), so with time held nothing turns stale and no goal
starts during the hold; the run then begins at t_0 as a lockstep run does.

Closed means, in lockstep, the actuator command stamped t_0 arrived (a node that is not
active answers with zeros, so the exchange goes on); in real time, every managed node of
``startup.nodes`` reported ``active`` (lifecycle ``get_state``), then a generalized force and
after it an actuator command arrived. After ``startup.timeout_s`` of wall time without that,
`LoopStartup.failure` names the node that did not answer. Times are nanoseconds of a wall
clock (only differences matter); nothing here reads a clock.

Example::

    startup = LoopStartup(StartupSettings(True, 60_000_000_000, ('controller',)),
                          realtime=True, start_ns=0)
    startup.node_state('controller', 'active')
    startup.generalized_force(10)
    startup.actuator_command(20)
    startup.closed  # True
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

#: Topic whose messages show the controller answering a state.
COMMAND_TOPIC = 'command/generalized_force'
#: Topic whose messages show the allocator answering a command.
ACTUATOR_TOPIC = 'command/actuators'
#: Node that publishes ``COMMAND_TOPIC`` in the shipped graph (named in failures).
CONTROLLER = 'controller'
#: Node that publishes ``ACTUATOR_TOPIC`` in the shipped graph (named in failures).
ALLOCATOR = 'thruster_allocator'


@dataclass(frozen=True)
class StartupSettings:
    """The simulator's ``startup.*`` parameters.

    Attributes:
        hold: Real time: hold the initial state until the loop is closed (False: step from
            the first tick, e.g. a simulator driven by hand).
        timeout_ns: Wall time for the loop to close before the simulator stops with an
            error (ns); 0 waits forever.
        nodes: Real time: managed nodes (names relative to the simulator's namespace) that
            must report ``active`` before physics starts.
        recorder: A node whose subscriptions to the state topics must be matched before
            the first state is published (``subscriber_matched``); '' none.
        mission: A mission's latched readiness topic (``mission/ready``) on which True
            must arrive before the first state is published; '' none.
        recorder_topics: The topics the recorder records (relative or absolute names); only
            the state topics among them are waited for; () every state topic.
    """

    hold: bool
    timeout_ns: int
    nodes: tuple[str, ...]
    recorder: str = ''
    mission: str = ''
    recorder_topics: tuple[str, ...] = ()


class LoopStartup:
    """Whether the loop is closed and, when it is not in time, which node did not answer."""

    def __init__(self, settings: StartupSettings, realtime: bool, start_ns: int) -> None:
        """Start waiting at ``start_ns`` (wall clock, ns).

        Args:
            settings: The ``startup.*`` parameters.
            realtime: Real time (lifecycle states count) or lockstep (answers only).
            start_ns: When the simulator first published the initial state.
        """
        self.settings = settings
        self.realtime = realtime
        self.start_ns = start_ns
        self._states: dict[str, str | None] = dict.fromkeys(
            settings.nodes if realtime else (), None)
        self._all_active = not self._states
        self._commanded = False
        self.closed = False

    def node_state(self, name: str, label: str | None) -> None:
        """A node's lifecycle state (``get_state``); None: it has no ``get_state`` service."""
        if self.closed or name not in self._states:
            return
        self._states[name] = label if label is not None else 'not running'
        if all(state == 'active' for state in self._states.values()):
            if not self._all_active:
                self._commanded = False  # answers count from the moment all are active
            self._all_active = True
        else:
            self._all_active = False

    def generalized_force(self, answers_state: bool = True) -> None:
        """A generalized force command arrived (lockstep: whether stamped t_0)."""
        if answers_state and self._all_active:
            self._commanded = True

    def actuator_command(self, answers_state: bool = True) -> None:
        """An actuator command arrived (lockstep: whether stamped t_0); may close the loop."""
        if not answers_state or self.closed:
            return
        if not self.realtime or (self._all_active and self._commanded):
            self.closed = True

    def expired(self, now_ns: int) -> bool:
        """Whether the start-up timeout has passed without the loop closing."""
        timeout = self.settings.timeout_ns
        return not self.closed and timeout > 0 and now_ns - self.start_ns >= timeout

    def waiting_for(self) -> str:
        """What the hold waits for, as a log line says it."""
        if self.realtime and self._states:
            names = ', '.join(self._states)
            return f'{names} active and an actuator command answering the held state'
        return 'an actuator command answering the held state'

    def failure(self, now_ns: int, publishers: dict[str, Sequence[str]]) -> str:
        """The error of an expired start-up, naming the node that did not answer.

        Args:
            now_ns: Now (wall clock, ns).
            publishers: Node names publishing each topic (``COMMAND_TOPIC``,
                ``ACTUATOR_TOPIC``) as the ROS graph shows them.
        """
        waited = (now_ns - self.start_ns) * 1e-9
        head = (f'the control loop did not close within startup.timeout_s = '
                f'{self.settings.timeout_ns * 1e-9:g} s ({waited:.1f} s):')
        inactive = [f'{name} is {state or "silent (no answer from its get_state service)"}'
                    for name, state in self._states.items() if state != 'active']
        if inactive:
            return f'{head} {"; ".join(inactive)} (not active)'
        if not self._commanded:
            return f'{head} {_silent(CONTROLLER, COMMAND_TOPIC, publishers)}'
        return f'{head} {_silent(ALLOCATOR, ACTUATOR_TOPIC, publishers)}'


def subscriber_matched(subscriber: str, namespace: str,
                       endpoints: Sequence[tuple[str, str, bool]], matched: int) -> bool:
    """Whether a node subscribes to a topic and the publisher has matched it.

    The ROS graph names the subscribing nodes; the publisher's matched count does not, so
    the count must cover every subscription the graph shows whose QoS can match (a
    subscription that asks for more than the publisher offers never matches and must not
    hold the start forever).

    Args:
        subscriber: Node name, relative to ``namespace`` or absolute (``/uvms/recorder``).
        namespace: The simulator's namespace (``/uvms``).
        endpoints: The topic's subscriptions as the graph shows them: node name, node
            namespace, and whether its QoS is compatible with the publisher's.
        matched: Subscriptions the publisher has matched.

    >>> subscriber_matched('recorder', '/uvms', [('recorder', '/uvms', True)], 1)
    True
    >>> subscriber_matched('recorder', '/uvms', [('controller', '/uvms', True),
    ...                                          ('recorder', '/uvms', True)], 1)
    False
    """
    wanted = subscriber if subscriber.startswith('/') else (
        f'{namespace.rstrip("/")}/{subscriber}')
    names = {f'{ns.rstrip("/")}/{name}' for name, ns, _ in endpoints}
    return wanted in names and matched >= sum(1 for *_, compatible in endpoints if compatible)


def _silent(role: str, topic: str, publishers: dict[str, Sequence[str]]) -> str:
    """The node that did not answer on ``topic``, with the publishers the graph shows."""
    names = list(publishers.get(topic, ()))
    shown = ', '.join(names) if names else 'none (the node is not running or not configured)'
    return f'the {role} did not answer: no {topic} answered the held state (publishers: {shown})'
