"""Thruster faults on the real graph in lockstep: run-time injection and the rank-loss path.

The paper robot presses the Case I wall (``idle_wall`` and a ContactTask goal, as in
test_contact_task_graph); at 2.5 s two horizontal thrusters are switched off through the
allocator's ``fault_injection.thrusters`` parameter. Six thrusters are left but they cannot
produce every wrench (rank 5): the allocator says so on ``thrusters/health`` and
/diagnostics (ERROR), and the controller ends the goal ACTUATION_LOST.
"""

from __future__ import annotations

from typing import Any

import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from rclpy.parameter import Parameter
from test_contact_task_graph import Probe, run, wall_goal

from uvms_msgs.action import ContactTask
from uvms_msgs.msg import ThrusterHealth

FAULT_AT_S = 2.5


@pytest.fixture(scope='module')
def lost() -> Probe:
    """A 100 N press, two horizontals off at 2.5 s (at run time), a goal sent at 3.5 s."""
    def watch(probe: Probe) -> None:
        probe.notes['health'] = []
        probe.notes['levels'] = []
        probe.node.create_subscription(
            ThrusterHealth, 'thrusters/health',
            lambda m: probe.notes['health'].append((probe.now_s(), m)), 100)
        probe.node.create_subscription(
            DiagnosticArray, '/diagnostics',
            lambda m: probe.notes['levels'].extend(
                (s.level, s.message) for s in m.status if 'thruster health' in s.name), 10)

    def fail(probe: Probe) -> None:
        allocator = probe.graph.nodes['thruster_allocator']
        probe.notes['bad'] = allocator.set_parameters([Parameter(
            'fault_injection.thrusters', value='index=0 kind=melted at_s=0')])[0]
        probe.notes['set'] = allocator.set_parameters([Parameter(
            'fault_injection.thrusters',
            value=f'index=0 kind=off at_s={FAULT_AT_S}; index=1 kind=off at_s={FAULT_AT_S}')])[0]

    return run(5.0, [(0.0, watch), (0.05, lambda p: p.send('press', wall_goal(press_s=4.0))),
                     (2.4, fail), (3.5, lambda p: p.send('again', wall_goal(start_s=3.6)))])


def test_bad_fault_at_run_time_is_refused_with_the_reason(lost: Probe) -> None:
    """An unknown kind is refused naming the parameter; a good one is taken."""
    assert not lost.notes['bad'].successful
    assert 'fault_injection.thrusters' in lost.notes['bad'].reason
    assert lost.notes['set'].successful


def test_rank_loss_ends_the_goal_actuation_lost(lost: Probe) -> None:
    """The goal that was pressing ends with ACTUATION_LOST, after the fault."""
    _, result = lost.results['press']
    assert result.error_code == ContactTask.Result.ACTUATION_LOST, result.error_string
    assert 'rank' in result.error_string


def test_health_reports_the_two_failed_thrusters_and_the_rank(lost: Probe) -> None:
    """thrusters/health: fully actuated before the fault; after it, 0 and 1 failed, rank 5."""
    health: list[tuple[float, Any]] = lost.notes['health']
    assert health and all(m.fully_actuated for t, m in health if t < FAULT_AT_S)
    last = health[-1][1]
    assert list(last.status)[:2] == [2, 2] and not any(list(last.status)[2:])
    assert last.rank == 5 and not last.fully_actuated
    first_lost = min(t for t, m in health if not m.fully_actuated)
    assert FAULT_AT_S < first_lost < FAULT_AT_S + 1.0


def test_diagnostics_say_error_once_not_fully_actuated(lost: Probe) -> None:
    """The allocator's 'thruster health' check goes from OK to ERROR."""
    levels = [level for level, _ in lost.notes['levels']]
    assert DiagnosticStatus.OK in levels
    assert levels[-1] == DiagnosticStatus.ERROR
    assert 'rank 5' in lost.notes['levels'][-1][1]


def test_goal_sent_while_actuation_is_lost_ends_actuation_lost(lost: Probe) -> None:
    """A goal accepted after the loss ends ACTUATION_LOST at the next health message."""
    _, result = lost.results['again']
    assert result.error_code == ContactTask.Result.ACTUATION_LOST, result.error_string
