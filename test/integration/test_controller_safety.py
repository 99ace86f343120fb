"""The controller node survives every command sequence of issue 28 and ends in a safe state.

The real ControllerNode (and ThrusterAllocatorNode) on an rclpy executor in lockstep, fed by
the probe of test_control_nodes: set_parameters through the node's own service, ContactTask
goals through an ActionClient, lifecycle transitions, input gaps and an allocator that
deactivates. Each test is one finding of the issue (see its docstring).
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
from action_msgs.msg import GoalStatus
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import Point, Vector3
from rcl_interfaces.srv import SetParameters, SetParametersAtomically
from rclpy.action import ActionClient
from rclpy.parameter import Parameter
from rosgraph_msgs.msg import Clock
from test_control_nodes import ARM, MS, Harness, set_sim_time, stamp_ns, tau_of
from uvms_control.controller_node import ControllerNode
from uvms_thrusters.thruster_allocator_node import ThrusterAllocatorNode

from uvms_model import UvmsModel
from uvms_msgs.action import ContactTask

X_HOLD = UvmsModel().ee_position(np.array([0.0] * 6 + ARM))
Result = ContactTask.Result


@pytest.fixture
def harness() -> Iterator[Harness]:
    """A fresh in-process graph with the probe."""
    h = Harness()
    yield h
    h.close()


class Tasks:
    """An action client on the probe: goals by name, their results."""

    def __init__(self, harness: Harness) -> None:
        self.harness = harness
        self.client = ActionClient(harness.probe.node, ContactTask, 'controller/contact_task')
        self.results: dict[str, Any] = {}
        self.handles: dict[str, Any] = {}

    def send(self, name: str, goal: ContactTask.Goal) -> None:
        """Send a goal and wait until the controller accepted it."""
        assert self.harness.spin_until(lambda: self.client.server_is_ready())
        future = self.client.send_goal_async(goal)
        assert self.harness.spin_until(future.done)
        handle = future.result()
        self.handles[name] = handle
        handle.get_result_async().add_done_callback(
            lambda r: self.results.__setitem__(name, r.result()))

    def result(self, name: str) -> Any:
        """Spin until the goal's result is in; the result message."""
        assert self.harness.spin_until(lambda: name in self.results), f'no result for {name}'
        return self.results[name].result


def motion_goal(start_s: float = 0.0, force_n: float = 0.0, duration_s: float = 5.0,
                ) -> ContactTask.Goal:
    """1 cm down from the hold point over duration_s, starting at start_s (0: at once)."""
    goal = ContactTask.Goal()
    goal.header.frame_id = 'map_ned'
    goal.header.stamp.sec, goal.header.stamp.nanosec = int(start_s), round(start_s % 1 * 1e9)
    x, y, z = X_HOLD.tolist()
    goal.path = [Point(x=x, y=y, z=z), Point(x=x, y=y, z=z + 0.01)]
    goal.time_from_start_s = [0.0, duration_s]
    goal.normal = Vector3(x=1.0, y=0.0, z=0.0)
    goal.force_n = force_n
    goal.force_ramp_s = 0.5
    return goal


def step(harness: Harness, t_ns: int, **kwargs: Any) -> Any:
    """Send the state of t_ns and spin until the command stamped t_ns is in; that command."""
    probe = harness.probe
    probe.send_state(t_ns, **kwargs)
    assert harness.spin_until(lambda: any(stamp_ns(c) == t_ns for c in probe.commands))
    return [c for c in probe.commands if stamp_ns(c) == t_ns][-1]


def state_at(harness: Harness, t_ns: int) -> Any:
    """The controller/state stamped t_ns."""
    assert harness.spin_until(lambda: any(stamp_ns(s) == t_ns for s in harness.probe.states))
    return [s for s in harness.probe.states if stamp_ns(s) == t_ns][-1]


def xyz(point: Any) -> np.ndarray:
    """A Point or Vector3 as an array."""
    return np.array([point.x, point.y, point.z])


# ------------------------------------------------------------------------ gains (findings 2, 7)


def set_parameters_service(harness: Harness, service: type, parameters: list[Parameter]) -> Any:
    """Call the controller's set_parameters(_atomically) service from the probe; the response."""
    name = ('controller/set_parameters_atomically' if service is SetParametersAtomically
            else 'controller/set_parameters')
    client = harness.probe.node.create_client(service, name)
    assert harness.spin_until(lambda: client.service_is_ready())
    future = client.call_async(service.Request(
        parameters=[parameter.to_parameter_msg() for parameter in parameters]))
    assert harness.spin_until(future.done)
    return future.result()


def test_set_parameters_with_a_null_space_list_one_too_long_is_refused_and_the_node_lives(
        harness: Harness) -> None:
    """The live case: 10 null-space values on a 9-DOF robot are refused; the node lives.

    Through the set_parameters service, as `ros2 param set` calls it; the controller then
    answers the next state.
    """
    node = harness.add(ControllerNode)
    step(harness, 0)
    response = set_parameters_service(harness, SetParameters, [
        Parameter('null_space.stiffness_1_s2', value=[4.0] * 10)])
    (answer,) = response.results
    assert not answer.successful
    assert 'null_space.stiffness_1_s2' in answer.reason
    assert len(node.get_parameter('null_space.stiffness_1_s2').value) == 9
    assert np.all(np.isfinite(tau_of(step(harness, 2 * MS))))


def test_an_atomic_call_is_checked_whole_before_anything_changes(harness: Harness) -> None:
    """An atomic call with a good stiffness and a bad null-space list changes nothing."""
    node = harness.add(ControllerNode)
    step(harness, 0)
    response = set_parameters_service(harness, SetParametersAtomically, [
        Parameter('impedance.stiffness_n_m', value=[6000.0] * 3),
        Parameter('null_space.stiffness_1_s2', value=[4.0] * 10)])
    assert not response.result.successful
    assert 'null_space.stiffness_1_s2' in response.result.reason
    assert list(node.get_parameter('impedance.stiffness_n_m').value) == [3000.0] * 3
    np.testing.assert_array_equal(node.core.impedance.K, 3000.0 * np.eye(3))
    assert np.all(np.isfinite(tau_of(step(harness, 2 * MS))))


@pytest.mark.parametrize(('name', 'value'), [
    ('impedance.inertia_kg', [0.01] * 3),
    ('hybrid.force_kp', 1000.0),
    ('impedance.stiffness_n_m', [1.0e9] * 3),
], ids=['inertia-0.01kg', 'force-kp-1000', 'stiffness-1e9'])
def test_unstable_gains_are_refused_at_run_time(harness: Harness, name: str,
                                                value: Any) -> None:
    """The review's gains whose sampled loops diverge at 500 Hz: refused with the reason."""
    node = harness.add(ControllerNode)
    step(harness, 0)
    (answer,) = node.set_parameters([Parameter(name, value=value)])
    assert not answer.successful
    assert name in answer.reason and 'spectral radius' in answer.reason
    (fine,) = node.set_parameters([Parameter('impedance.stiffness_n_m', value=[2500.0] * 3)])
    assert fine.successful


def test_contact_threshold_above_a_waiting_goals_force_is_refused(harness: Harness) -> None:
    """A contact threshold above a waiting goal's force is refused; the goal then starts.

    It used to be taken, and the step raised out of the executor at the goal's start.
    """
    node = harness.add(ControllerNode)
    tasks = Tasks(harness)
    step(harness, 0)
    tasks.send('waiting', motion_goal(start_s=0.02, force_n=20.0))
    (answer,) = node.set_parameters([Parameter('force.contact_threshold_n', value=50.0)])
    assert not answer.successful and 'force.contact_threshold_n' in answer.reason
    for k in range(1, 21):
        step(harness, 2 * MS * k)
    assert node._faults.count == 0
    assert node.supervisor.progress() is not None  # following its path


# ------------------------------------------------------------------------ nothing escapes (2)


def test_goal_before_the_first_step_after_reactivation_runs(harness: Harness) -> None:
    """Deactivate, activate, a goal before the first step: it waits for that step and runs.

    The reference used to hold no point yet and the step raised out of the executor.
    """
    node = harness.add(ControllerNode)
    tasks = Tasks(harness)
    step(harness, 0)
    node.trigger_deactivate()
    node.trigger_activate()
    tasks.send('early', motion_goal())
    for k in range(1, 6):
        command = step(harness, 2 * MS * k)
        assert np.any(tau_of(command) != 0.0)
    assert node._faults.count == 0
    assert node.supervisor.progress() is not None
    np.testing.assert_allclose(xyz(state_at(harness, 2 * MS).desired_position), X_HOLD,
                               atol=1e-6)


def controller_status(msg: DiagnosticArray) -> DiagnosticStatus | None:
    """The controller's 'control' status of a diagnostics message."""
    return next((s for s in msg.status if s.name == 'controller: control'), None)


def test_an_exception_in_the_control_step_gives_zero_ends_the_task_and_reports_error(
        harness: Harness) -> None:
    """Any exception in the step: zero command, task ended, ERROR on /diagnostics; node lives.

    The zero command carries the state's stamp, the diagnostics the exception text; the next
    state is controlled again.
    """
    node = harness.add(ControllerNode)
    tasks = Tasks(harness)
    diagnostics: list[DiagnosticArray] = []
    harness.probe.node.create_subscription(DiagnosticArray, '/diagnostics', diagnostics.append,
                                           10)
    step(harness, 0)
    tasks.send('running', motion_goal())
    step(harness, 2 * MS)
    real_step = node.supervisor.step

    def broken(*args: Any) -> Any:
        raise RuntimeError('injected fault')
    node.supervisor.step = broken
    np.testing.assert_array_equal(tau_of(step(harness, 4 * MS)), 0.0)
    assert tasks.result('running').error_code == Result.INACTIVE
    assert 'injected fault' in tasks.result('running').error_string
    node.supervisor.step = real_step
    assert np.any(tau_of(step(harness, 6 * MS)) != 0.0)
    assert harness.spin_until(lambda: any(
        (s := controller_status(m)) is not None and s.level == DiagnosticStatus.ERROR
        for m in diagnostics), timeout_s=5.0)
    status = next(s for m in diagnostics if (s := controller_status(m)) is not None
                  and s.level == DiagnosticStatus.ERROR)
    assert 'injected fault' in status.message
    assert {v.key: v.value for v in status.values}['faults'] == '1'


# ------------------------------------------------------------------------ stale inputs (8)


def test_stale_wrench_ends_the_running_goal_inputs_stale_and_control_resumes_holding(
        harness: Harness) -> None:
    """No wrench for 0.3 s: zero command, the goal ends INPUTS_STALE, then a fresh hold.

    With the inputs back the hold point is the position measured then.
    """
    harness.add(ControllerNode)
    tasks = Tasks(harness)
    step(harness, 0)
    tasks.send('running', motion_goal())
    for k in range(1, 5):
        step(harness, 2 * MS * k)
    probe = harness.probe
    for k in range(5, 160):
        probe.send_state(2 * MS * k, skip=('wrench',))
    assert harness.spin_until(lambda: stamp_ns(probe.commands[-1]) == 2 * MS * 159)
    np.testing.assert_array_equal(tau_of(probe.commands[-1]), 0.0)
    assert tasks.result('running').error_code == Result.INPUTS_STALE
    moved = [0.0, 0.5, -1.45]
    step(harness, 2 * MS * 160, arm=moved)
    state = state_at(harness, 2 * MS * 160)
    np.testing.assert_allclose(xyz(state.desired_position), xyz(state.position), atol=1e-9)
    np.testing.assert_allclose(xyz(state.desired_velocity), 0.0)


def test_a_two_second_gap_between_states_ends_the_goal_and_recaptures_the_hold(
        harness: Harness) -> None:
    """A 2 s gap in all states ends the goal INPUTS_STALE and holds where the arm is.

    X_d used to jump 2 s along the path, and the force integral took in the whole gap.
    """
    node = harness.add(ControllerNode)
    tasks = Tasks(harness)
    step(harness, 0)
    tasks.send('running', motion_goal(duration_s=1.0))
    for k in range(1, 5):
        step(harness, 2 * MS * k)
    step(harness, 2_008 * MS)
    assert tasks.result('running').error_code == Result.INPUTS_STALE
    state = state_at(harness, 2_008 * MS)
    np.testing.assert_allclose(xyz(state.desired_position), xyz(state.position), atol=1e-9)
    assert node._faults.count == 0


def test_inactive_allocator_ends_the_goal_and_zeroes_the_command_until_it_is_back(
        harness: Harness) -> None:
    """Allocator deactivated: zero commands and the goal ends INPUTS_STALE; then it resumes.

    The controller learns it from the allocator's transition_event; once the allocator is
    active again, control resumes holding the measured position.
    """
    node = harness.add(ControllerNode)
    allocator = harness.add(ThrusterAllocatorNode)
    tasks = Tasks(harness)
    step(harness, 0)
    tasks.send('running', motion_goal())
    step(harness, 2 * MS)
    allocator.trigger_deactivate()
    zero_from = first_state_answered(harness, 2, lambda tau: np.all(tau == 0.0))
    for k in range(zero_from + 1, zero_from + 4):
        np.testing.assert_array_equal(tau_of(step(harness, 2 * MS * k)), 0.0)
    assert tasks.result('running').error_code == Result.INPUTS_STALE
    allocator.trigger_activate()
    k = first_state_answered(harness, zero_from + 4, lambda tau: np.any(tau != 0.0))
    state = state_at(harness, 2 * MS * k)
    np.testing.assert_allclose(xyz(state.desired_position), xyz(state.position), atol=1e-9)
    assert node._faults.count == 0


def first_state_answered(harness: Harness, k0: int, answer: Any, most: int = 200) -> int:
    """Send states k0, k0 + 1, ... (2 ms apart) until a command satisfies answer(tau)."""
    for k in range(k0, k0 + most):
        if answer(tau_of(step(harness, 2 * MS * k))):
            return k
    raise AssertionError(f'no such command in {most} states')


# ------------------------------------------------------------------------ lifecycle (9)


def test_goal_queued_before_the_first_step_ends_inactive_at_deactivation(
        harness: Harness) -> None:
    """A goal sent before any state (queued for the first step) gets its result INACTIVE."""
    node = harness.add(ControllerNode)
    tasks = Tasks(harness)
    tasks.send('queued', motion_goal())
    node.trigger_deactivate()
    assert tasks.result('queued').error_code == Result.INACTIVE
    assert tasks.results['queued'].status == GoalStatus.STATUS_ABORTED


def test_streamed_target_does_not_survive_deactivate_activate(harness: Harness) -> None:
    """A hold target streamed before deactivation is dropped at activation.

    After activation the first step holds the measured position and stays there.
    """
    node = harness.add(ControllerNode)
    step(harness, 0)
    node.supervisor.set_target((X_HOLD + np.array([0.05, 0.0, 0.0])).tolist())
    node.trigger_deactivate()
    node.trigger_activate()
    for k in range(1, 30):
        step(harness, 2 * MS * k)
    state = state_at(harness, 2 * MS * 29)
    np.testing.assert_allclose(xyz(state.desired_position), X_HOLD, atol=1e-9)


def test_goal_after_reactivation_is_checked_against_the_new_position(harness: Harness) -> None:
    """After deactivate/activate a goal is checked against X of the first new step.

    The arm moved 5 cm while the controller was inactive; a goal 1 cm from the new X (and
    6 cm from the old one) is within safety.max_path_distance_m = 0.03 m only from the new.
    """
    node = harness.add(ControllerNode, **{'safety.max_path_distance_m': 0.03})
    tasks = Tasks(harness)
    step(harness, 0)
    node.trigger_deactivate()
    moved = [0.0, 0.55, -1.511]
    x_moved = UvmsModel().ee_position(np.array([0.0] * 6 + moved))
    assert 0.04 < float(np.linalg.norm(x_moved - X_HOLD)) < 0.06
    node.trigger_activate()
    goal = motion_goal()
    x, y, z = x_moved.tolist()
    goal.path = [Point(x=x, y=y, z=z), Point(x=x, y=y, z=z + 0.01)]
    tasks.send('near_new', goal)
    for k in range(1, 4):
        step(harness, 2 * MS * k, arm=moved)
    assert 'near_new' not in tasks.results  # accepted and running, not refused
    assert node.supervisor.progress() is not None


def test_timer_mode_stale_inputs_end_the_goal_inputs_stale(harness: Harness) -> None:
    """Timer mode on simulated time: inputs 300 ms old give zero and end the goal INPUTS_STALE."""
    node = harness.add(ControllerNode, trigger_mode='timer', watchdog_timeout_s=0.1,
                       use_sim_time=True)
    tasks = Tasks(harness)
    probe = harness.probe
    clock_pub = probe.node.create_publisher(Clock, '/clock', 10)
    set_sim_time(harness, node, clock_pub, 3_000_000_000)
    probe.send_state(3_000_000_000)
    assert harness.spin_until(lambda: any(stamp_ns(c) == 3_000_000_000 for c in probe.commands))
    tasks.send('running', motion_goal())
    set_sim_time(harness, node, clock_pub, 3_300_000_000)
    assert tasks.result('running').error_code == Result.INPUTS_STALE
    assert harness.spin_until(lambda: any(stamp_ns(c) == 3_300_000_000 for c in probe.commands))
    np.testing.assert_array_equal(
        tau_of([c for c in probe.commands if stamp_ns(c) == 3_300_000_000][-1]), 0.0)
