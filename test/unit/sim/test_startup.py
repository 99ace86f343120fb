"""Tests of uvms_sim.startup: when the control loop is closed, and who did not answer."""

from __future__ import annotations

from uvms_sim.startup import LoopStartup, StartupSettings

S = 1_000_000_000
NODES = ('controller', 'thruster_allocator')


def realtime(timeout_s: float = 60.0) -> LoopStartup:
    """A real-time start-up waiting for both managed nodes."""
    return LoopStartup(StartupSettings(True, round(timeout_s * S), NODES), True, 0)


def test_lockstep_closes_with_the_actuator_command_of_the_held_state() -> None:
    """Lockstep needs no lifecycle state: the answer stamped t_0 closes the loop."""
    startup = LoopStartup(StartupSettings(True, 60 * S, NODES), False, 0)
    startup.actuator_command(answers_state=False)
    assert not startup.closed
    startup.actuator_command()
    assert startup.closed


def test_realtime_needs_active_nodes_then_a_command_then_an_actuation() -> None:
    """Answers before every node is active do not count; in order they close the loop."""
    startup = realtime()
    startup.generalized_force()
    startup.actuator_command()
    assert not startup.closed
    startup.node_state('controller', 'active')
    startup.node_state('thruster_allocator', 'active')
    startup.actuator_command()  # the allocator's timer: not yet an answer to the controller
    assert not startup.closed
    startup.generalized_force()
    startup.actuator_command()
    assert startup.closed


def test_a_node_leaving_active_resets_the_answers() -> None:
    """A controller's command seen while all were active counts only while they stay so."""
    startup = realtime()
    for name in NODES:
        startup.node_state(name, 'active')
    startup.generalized_force()
    startup.node_state('thruster_allocator', 'inactive')
    startup.node_state('thruster_allocator', 'active')
    startup.actuator_command()
    assert not startup.closed


def test_expires_only_after_the_timeout_and_never_with_zero() -> None:
    """startup.timeout_s of wall time; 0 waits forever."""
    assert not realtime(2.0).expired(S)
    assert realtime(2.0).expired(2 * S)
    assert not realtime(0.0).expired(10**6 * S)


def test_failure_names_the_node_that_is_not_active() -> None:
    """An unconfigured allocator and a controller without get_state are both named."""
    startup = realtime(5.0)
    startup.node_state('controller', None)
    startup.node_state('thruster_allocator', 'unconfigured')
    message = startup.failure(6 * S, {})
    assert 'startup.timeout_s = 5 s (6.0 s)' in message
    assert 'controller is not running' in message
    assert 'thruster_allocator is unconfigured (not active)' in message


def test_failure_names_the_controller_then_the_allocator_by_their_answers() -> None:
    """Active but silent: no command names the controller; no actuation the allocator."""
    startup = realtime()
    for name in NODES:
        startup.node_state(name, 'active')
    assert 'the controller did not answer' in startup.failure(61 * S, {})
    startup.generalized_force()
    message = startup.failure(61 * S, {'command/actuators': ['thruster_allocator']})
    assert 'the thruster_allocator did not answer' in message
    assert 'publishers: thruster_allocator' in message
