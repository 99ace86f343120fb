"""The task interface on the real graph in lockstep: goals, preemption, cancel, limits, lifecycle.

Each run is the whole graph of ``idle_wall`` (the paper's robot at point A, the Case I wall,
no mission) in one process on simulated time, with a probe node that acts at given simulated
times through the public interfaces: the ContactTask action, set_parameters, the lifecycle
transitions, and the topics a user would watch.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from action_msgs.msg import GoalStatus
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Point, PointStamped, Vector3
from rcl_interfaces.msg import Log
from rclpy.node import Node
from rclpy.parameter import Parameter
from uvms_control.task_server import REJECTED_PREFIX
from uvms_run.graph import Graph, build_graph, run_graph
from uvms_scenarios.scenario import load_scenario
from uvms_tasks.client import ContactTaskClient

from uvms_analysis import report
from uvms_msgs.action import ContactTask
from uvms_msgs.msg import ActuatorCommand, ContactState, ControllerState, GeneralizedForce

SCENARIOS = Path(__file__).resolve().parents[2] / 'config' / 'scenarios'
#: Point A of the scenario (m, map_ned) and the wall's x (m).
X0 = (1.70, 0.0, -0.10)
WALL_X = 1.7771
CONTROL_PERIOD_S = 0.002
Result = ContactTask.Result


def wall_goal(force_n: float = 100.0, press_s: float = 3.0, start_s: float = 0.2,
              depth_m: float = 0.023) -> ContactTask.Goal:
    """Toward the wall in 1.5 s, then along it (down 2 cm) for press_s, F_d = force_n."""
    goal = ContactTask.Goal()
    goal.header.frame_id = 'map_ned'
    goal.header.stamp.sec, goal.header.stamp.nanosec = int(start_s), round(start_s % 1 * 1e9)
    points = [X0, (WALL_X + depth_m, 0.0, -0.10), (WALL_X + depth_m, 0.0, -0.08)]
    goal.path = [Point(x=x, y=y, z=z) for x, y, z in points]
    goal.time_from_start_s = [0.0, 1.5, 1.5 + press_s]
    goal.normal = Vector3(x=1.0, y=0.0, z=0.0)
    goal.force_n = force_n
    goal.force_ramp_s = 0.5
    goal.require_contact = True
    return goal


@dataclass
class Probe:
    """What the probe node saw during a run."""

    node: Node
    client: ContactTaskClient
    graph: Graph
    feedback: dict[str, list[tuple[float, Any]]] = field(default_factory=dict)
    results: dict[str, tuple[int, Any]] = field(default_factory=dict)
    handles: dict[str, Any] = field(default_factory=dict)
    contact: list[tuple[float, float]] = field(default_factory=list)
    commands: list[tuple[float, np.ndarray]] = field(default_factory=list)
    actuators: list[tuple[float, float]] = field(default_factory=list)
    diagnostics: set[str] = field(default_factory=set)
    desired: list[tuple[float, np.ndarray]] = field(default_factory=list)
    notes: dict[str, Any] = field(default_factory=dict)
    #: Reasons of the goals the controller rejected, from its /rosout lines, in order.
    rejections: list[str] = field(default_factory=list)

    def now_s(self) -> float:
        """Simulated time (s)."""
        return float(self.graph.simulator.sim_time_ns) * 1e-9

    def send(self, name: str, goal: ContactTask.Goal) -> None:
        """Send a goal; record its feedback and result (None if rejected) under ``name``."""
        self.feedback[name] = []
        future = self.client.send_goal_async(
            goal, lambda fb: self.feedback[name].append((self.now_s(), fb)))

        def accepted(done: Any) -> None:
            handle = done.result()
            self.handles[name] = handle
            if not handle.accepted:
                self.results[name] = (int(handle.status), None)
                return
            handle.get_result_async().add_done_callback(
                lambda r: self.results.__setitem__(name, (r.result().status, r.result().result)))
        future.add_done_callback(accepted)

    def cancel(self, name: str) -> None:
        """Ask the controller to cancel a goal."""
        self.handles[name].cancel_goal_async()

    def force_after(self, t_s: float) -> list[float]:
        """Ground-truth contact force (N) after simulated time t_s."""
        return [f for t, f in self.contact if t >= t_s]


Action = Callable[[Probe], None]


def generalized_force(msg: GeneralizedForce) -> np.ndarray:
    """Vehicle wrench and joint torques of a command as one vector."""
    force, torque = msg.vehicle_wrench.force, msg.vehicle_wrench.torque
    return np.array([force.x, force.y, force.z, torque.x, torque.y, torque.z,
                     *msg.joint_torques])


def run(duration_s: float, script: list[tuple[float, Action]], stiffness: float = 1.0e4,
        extra: dict[str, dict[str, Any]] | None = None,
        output_path: Path | None = None) -> Probe:
    """Run idle_wall in lockstep for duration_s, acting at the scripted simulated times.

    With ``output_path`` the recorder records the graph there.
    """
    scenario = load_scenario(SCENARIOS / 'idle_wall.yaml').with_changes(duration_s=duration_s)
    overrides = {'simulator': {'contact.stiffness_n_m': stiffness}, **(extra or {})}
    graph = build_graph(scenario, 'lockstep', extra_overrides=overrides,
                        output_path=output_path)
    node = Node('probe', namespace='/uvms', context=graph.context,
                parameter_overrides=[Parameter('use_sim_time', value=True)])
    probe = Probe(node, ContactTaskClient(node), graph)
    node.create_subscription(
        ContactState, 'contact',
        lambda m: probe.contact.append((probe.now_s(), float(m.force.x))), 100)
    node.create_subscription(
        GeneralizedForce, 'command/generalized_force',
        lambda m: probe.commands.append((probe.now_s(), generalized_force(m))), 100)
    node.create_subscription(
        ActuatorCommand, 'command/actuators',
        lambda m: probe.actuators.append(
            (probe.now_s(), float(np.abs(m.thrust).sum() + np.abs(m.joint_torques).sum()))),
        100)
    node.create_subscription(
        ControllerState, 'controller/state',
        lambda m: probe.desired.append((probe.now_s(), np.array(
            [m.desired_position.x, m.desired_position.y, m.desired_position.z]))), 100)
    node.create_subscription(
        DiagnosticArray, '/diagnostics',
        lambda m: probe.diagnostics.update(status.name for status in m.status), 10)
    node.create_subscription(
        Log, '/rosout', lambda m: probe.rejections.append(m.msg[len(REJECTED_PREFIX):])
        if m.name.endswith('controller') and m.msg.startswith(REJECTED_PREFIX) else None, 100)
    probe.notes['target_pub'] = node.create_publisher(PointStamped, 'controller/target_position',
                                                      10)
    graph.nodes['probe'] = node
    pending = sorted(script, key=lambda item: item[0])

    def on_spin(_: Graph) -> None:
        while pending and probe.now_s() >= pending[0][0] and probe.client.server_is_ready():
            pending.pop(0)[1](probe)

    result = run_graph(graph, on_spin=on_spin)
    assert not result.interrupted
    probe.notes['end_s'] = result.sim_time_s
    assert not pending, f'script actions never ran: {pending}'
    return probe


@pytest.fixture(scope='module')
def press() -> Probe:
    """A 100 N press on the Case I wall, invalid goals meanwhile, a gain changed, 6.5 s."""
    def invalid(probe: Probe) -> None:
        for name, change in INVALID.items():
            goal = wall_goal()
            change(goal)
            probe.send(name, goal)

    def gains(probe: Probe) -> None:
        controller = probe.graph.nodes['controller']
        probe.notes['good'] = controller.set_parameters(
            [Parameter('impedance.stiffness_n_m', value=[2500.0, 2500.0, 2500.0])])[0]
        probe.notes['bad'] = controller.set_parameters(
            [Parameter('hybrid.force_kp', value=-1.0)])[0]
        probe.notes['read_only'] = controller.set_parameters(
            [Parameter('model.mass_scale', value=0.5)])[0]
        probe.notes['stiffness'] = controller.core.impedance.K.copy()
        probe.notes['force_kp'] = controller.core.hybrid.k_fp

    return run(6.5, [(0.05, lambda p: p.send('press', wall_goal())),
                     (0.1, invalid), (0.3, gains)])


#: Goals that must be refused, and the field the refusal names.
INVALID: dict[str, Callable[[ContactTask.Goal], None]] = {
    'one_point': lambda g: setattr(g, 'path', g.path[:1]),
    'times_not_increasing': lambda g: setattr(g, 'time_from_start_s', [0.0, 2.0, 1.0]),
    'times_unequal_length': lambda g: setattr(g, 'time_from_start_s', [0.0, 1.0]),
    'nan_point': lambda g: setattr(g.path[1], 'x', math.nan),
    'zero_normal': lambda g: setattr(g, 'normal', Vector3()),
    'negative_force': lambda g: setattr(g, 'force_n', -5.0),
    'force_over_limit': lambda g: setattr(g, 'force_n', 1.0e4),
    'far_point': lambda g: setattr(g.path[2], 'z', 3.0),
    'other_frame': lambda g: setattr(g.header, 'frame_id', 'base_link'),
}
FIELDS = {'one_point': 'path', 'times_not_increasing': 'time_from_start_s[2]',
          'times_unequal_length': 'time_from_start_s', 'nan_point': 'path',
          'zero_normal': 'normal', 'negative_force': 'force_n',
          'force_over_limit': 'force_n', 'far_point': 'path[2]',
          'other_frame': 'header.frame_id'}


def test_press_on_the_wall_settles_and_succeeds_with_its_figures(press: Probe) -> None:
    """100 N on the Case I wall: contact, force within 5 % of F_d, SUCCEEDED with figures."""
    status, result = press.results['press']
    assert status == GoalStatus.STATUS_SUCCEEDED
    assert result.error_code == Result.SUCCEEDED, result.error_string
    assert result.contact_time_s > 2.0
    assert 95.0 < result.peak_force_n < 140.0
    assert result.settling_time_s < 1.5
    assert result.rms_force_error_n < 5.0  # 5 % of F_d
    settled = [f for t, f in press.contact if 3.0 <= t <= 4.5]
    assert settled and all(abs(f - 100.0) < 5.0 for f in settled)


def test_feedback_arrives_at_ten_hertz_or_more(press: Probe) -> None:
    """Feedback during the task: at least 10 per simulated second, phases and W in range."""
    feedback = press.feedback['press']
    span = feedback[-1][0] - feedback[0][0]
    assert span > 3.0 and len(feedback) >= 10 * span
    phases = {fb.phase for _, fb in feedback}
    assert ContactTask.Feedback.PHASE_CONSTRAINED in phases
    assert all(0.0 <= fb.weight <= 1.0 and 0.0 <= fb.progress <= 1.0 for _, fb in feedback)


@pytest.mark.parametrize('name', list(INVALID))
def test_invalid_goal_is_rejected_and_the_controller_log_names_its_field(
        press: Probe, name: str) -> None:
    """A goal that fails the checks is rejected; the controller's log line names the field.

    No result (ROS 2 actions give a rejected goal none): the reason is on /rosout. The
    running task goes on (``test_press_on_the_wall_settles_and_succeeds_with_its_figures``).
    """
    _, result = press.results[name]
    assert result is None and not press.handles[name].accepted
    assert len(press.rejections) == len(INVALID), press.rejections
    reason = press.rejections[list(INVALID).index(name)]  # the goals are sent in this order
    assert reason.startswith(FIELDS[name]), reason


def test_gain_changed_at_run_time_takes_effect_and_a_bad_one_changes_nothing(
        press: Probe) -> None:
    """set_parameters: a valid stiffness is used at once; a bad or read-only value is refused."""
    assert press.notes['good'].successful
    np.testing.assert_allclose(np.diag(press.notes['stiffness']), [2500.0] * 3)
    bad = press.notes['bad']
    assert not bad.successful and 'hybrid.force_kp' in bad.reason
    assert press.notes['force_kp'] == 0.05  # unchanged
    assert not press.notes['read_only'].successful


def test_diagnostics_carry_every_node(press: Probe) -> None:
    """/diagnostics has statuses from simulator, controller, allocator, visualizer."""
    nodes = {name.split(':')[0] for name in press.diagnostics}
    assert {'simulator', 'controller', 'thruster_allocator', 'visualizer'} <= nodes


@pytest.fixture(scope='module')
def preempt_and_cancel() -> Probe:
    """A press preempted by a second one, which is then canceled in contact, 7 s."""
    return run(7.0, [(0.05, lambda p: p.send('first', wall_goal(press_s=6.0))),
                     (2.5, lambda p: p.send('second', wall_goal(80.0, start_s=0.0))),
                     (4.5, lambda p: p.cancel('second'))])


def test_new_goal_preempts_the_running_one(preempt_and_cancel: Probe) -> None:
    """The first goal ends PREEMPTED when the second arrives."""
    status, result = preempt_and_cancel.results['first']
    assert result.error_code == Result.PREEMPTED
    assert status == GoalStatus.STATUS_ABORTED


def test_cancel_in_contact_releases_the_force_within_two_seconds(
        preempt_and_cancel: Probe) -> None:
    """Canceled while pressing: CANCELED, contact force below 5 N within 2 s."""
    status, result = preempt_and_cancel.results['second']
    assert result.error_code == Result.CANCELED and status == GoalStatus.STATUS_CANCELED
    assert max(f for t, f in preempt_and_cancel.contact if 4.0 <= t <= 4.5) > 50.0
    assert max(preempt_and_cancel.force_after(6.5)) < 5.0


def test_force_limit_ends_the_task_and_the_arm_backs_off() -> None:
    """A limit lowered below F_d on a stiff wall: FORCE_LIMIT naming it, then no contact."""
    probe = run(5.5, [(0.05, lambda p: p.send('press', wall_goal(100.0, press_s=4.0))),
                      (2.6, lambda p: p.graph.nodes['controller'].set_parameters(
                          [Parameter('safety.max_contact_force_n', value=60.0)]))],
                stiffness=1.0e5)
    status, result = probe.results['press']
    assert status == GoalStatus.STATUS_ABORTED
    assert result.error_code == Result.FORCE_LIMIT
    assert 'safety.max_contact_force_n' in result.error_string
    assert max(probe.force_after(4.5)) < 1.0


def test_inactive_allocator_commands_zero_and_inactive_controller_does_not_stall() -> None:
    """Allocator off: zero actuators within two periods, on again: they resume; controller off.

    With the controller inactive the lockstep run still reaches its end, on zero commands.
    """
    def deactivate(probe: Probe) -> None:
        probe.notes['off_at'] = probe.now_s()
        probe.graph.nodes['thruster_allocator'].trigger_deactivate()

    def activate(probe: Probe) -> None:
        probe.notes['on_at'] = probe.now_s()
        probe.graph.nodes['thruster_allocator'].trigger_activate()

    probe = run(2.0, [(0.4, deactivate), (0.8, activate),
                      (1.2, lambda p: p.graph.nodes['controller'].trigger_deactivate())])
    off, on = probe.notes['off_at'], probe.notes['on_at']
    after_off = [a for t, a in probe.actuators if off + 2 * CONTROL_PERIOD_S < t < on]
    assert after_off and max(after_off) == 0.0
    assert max(a for t, a in probe.actuators if on + 0.1 < t < 1.2) > 0.0
    assert probe.notes['end_s'] >= 2.0 - 1e-9  # the run reached its end: nothing stalled
    after_controller_off = [c for t, c in probe.commands if t > 1.2 + 2 * CONTROL_PERIOD_S]
    assert after_controller_off and all(np.all(c == 0.0) for c in after_controller_off)


def target(frame: str, x: float) -> Action:
    """Publish a hold target at (x, 0, -0.10) in ``frame``."""
    def act(probe: Probe) -> None:
        msg = PointStamped()
        msg.header.frame_id = frame
        msg.point.x, msg.point.y, msg.point.z = x, 0.0, -0.10
        probe.notes['target_pub'].publish(msg)
    return act


def test_streamed_target_moves_the_hold_point_at_its_speed_limit() -> None:
    """A map_ned target moves X_d at most 0.1 m/s toward it; another frame is refused."""
    probe = run(1.2, [(0.1, target('map_ned', X0[0] + 0.05)), (0.7, target('base_link', 1.0))])
    x_d = {round(t, 3): x for t, x in probe.desired}
    assert x_d[0.1][0] == pytest.approx(X0[0], abs=1e-3)
    moved = x_d[0.4][0] - x_d[0.2][0]
    assert 0.01 < moved <= 0.02 + 1e-6  # 0.2 s at the 0.1 m/s limit
    assert x_d[0.7][0] == pytest.approx(X0[0] + 0.05, abs=1e-6)  # reached, then held
    assert x_d[1.1][0] == pytest.approx(X0[0] + 0.05, abs=1e-6)  # base_link target refused


@pytest.fixture(scope='module')
def two_presses(tmp_path_factory: pytest.TempPathFactory) -> tuple[Probe, Path]:
    """Two tasks in a row, recorded: 100 N, then 60 N once the first has ended."""
    path = tmp_path_factory.mktemp('two_presses') / 'two_presses.mcap'

    def second(probe: Probe) -> None:
        assert 'first' in probe.results, 'the first press has not ended yet'
        probe.send('second', wall_goal(force_n=60.0, press_s=2.0, start_s=0.0))

    # The first ends once its force is released and the contact let go (about 6 s).
    probe = run(12.5, [(0.05, lambda p: p.send('first', wall_goal())), (7.0, second)],
                output_path=path)
    return probe, path


def test_recording_of_two_tasks_reports_each_tasks_result_figures(
        two_presses: tuple[Probe, Path], capsys: pytest.CaptureFixture[str]) -> None:
    """`uvms report`: one row per task, ground truth by default; the result's from F_e."""
    probe, path = two_presses
    assert report.main([str(path), '--format', 'csv']) == 0
    default = list(csv.DictReader(io.StringIO(capsys.readouterr().out)))
    assert [row['force_source'] for row in default] == ['contact', 'contact']  # as the plots
    assert report.main([str(path), '--format', 'csv', '--force-source', 'controller']) == 0
    rows = list(csv.DictReader(io.StringIO(capsys.readouterr().out)))
    assert len(rows) == 2
    for row, name, force_n in zip(rows, ('first', 'second'), (100.0, 60.0), strict=True):
        _, result = probe.results[name]
        assert result.error_code == Result.SUCCEEDED, result.error_string
        assert row['task'] == bytes(probe.handles[name].goal_id.uuid).hex()
        assert float(row['desired_force_N']) == force_n
        assert row['force_source'] == 'controller'
        assert float(row['contact_duration_s']) > 1.0
        assert row['contact_duration_s'] == f'{result.contact_time_s:.6g}'
        assert row['peak_force_N'] == f'{result.peak_force_n:.6g}'
        assert row['settling_time_s'] == f'{result.settling_time_s:.6g}'
        assert row['force_rms_error_N'] == f'{result.rms_force_error_n:.6g}'
