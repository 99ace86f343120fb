"""The thruster allocator as a managed node: autostart, zeros when inactive, lifecycle services."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import rclpy
from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from lifecycle_msgs.msg import State, Transition
from lifecycle_msgs.srv import ChangeState, GetState
from rclpy.context import Context
from rclpy.executors import Executor
from rclpy.lifecycle import TransitionCallbackReturn
from rclpy.node import Node
from rclpy.parameter import Parameter
from std_msgs.msg import Header
from uvms_common.lifecycle import state_label
from uvms_common.node_main import make_executor
from uvms_thrusters.errors import ThrusterParameterError
from uvms_thrusters.thruster_allocator_node import ThrusterAllocatorNode

from uvms_msgs.msg import ActuatorCommand, GeneralizedForce, ThrusterState

CONFIG = Path(__file__).resolve().parents[2] / 'config'
PARAMS = ['--ros-args', '--params-file', str(CONFIG / 'robot.yaml'),
          '--params-file', str(CONFIG / 'controller.yaml')]
JOINTS = ('joint_1', 'joint_2', 'joint_3')
PERIOD_NS = 2_000_000  # the 500 Hz control period
TAU = [40.0, 0.0, 10.0, 0.0, 5.0, 0.0, 1.0, 2.0, 3.0]
SERVICE = '/uvms/thruster_allocator/'
SUCCESS = TransitionCallbackReturn.SUCCESS


def stamp_ns(msg: Any) -> int:
    """Header stamp of a message (ns)."""
    return msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec


def is_zero(msg: ActuatorCommand) -> bool:
    """Zero thrust on every thruster and zero torque on every joint."""
    return not any(msg.thrust) and not any(msg.joint_torques) and len(msg.thrust) == 8


class Graph:
    """A context, an EventsExecutor, the allocator in /uvms and a probe node that drives it."""

    def __init__(self) -> None:
        self.context = Context()
        rclpy.init(args=[], context=self.context)
        self.executor: Executor = make_executor('events', self.context)
        self.probe = Node('probe', namespace='uvms', context=self.context)
        self.commands = self.probe.create_publisher(
            GeneralizedForce, 'command/generalized_force', 10)
        self.actuators: list[ActuatorCommand] = []
        self.thruster_states: list[ThrusterState] = []
        self.diagnostics: list[DiagnosticArray] = []
        self.probe.create_subscription(ActuatorCommand, 'command/actuators',
                                       self.actuators.append, 100)
        self.probe.create_subscription(ThrusterState, 'thrusters/state',
                                       self.thruster_states.append, 100)
        self.probe.create_subscription(DiagnosticArray, '/diagnostics',
                                       self.diagnostics.append, 10)
        self.executor.add_node(self.probe)
        self.nodes: list[Node] = [self.probe]

    def allocator(self, **overrides: Any) -> ThrusterAllocatorNode:
        """The allocator in /uvms from the config files plus overrides, spinning."""
        node = ThrusterAllocatorNode(
            namespace='uvms', context=self.context, cli_args=PARAMS,
            parameter_overrides=[Parameter(k, value=v) for k, v in overrides.items()])
        self.executor.add_node(node)
        self.nodes.append(node)
        return node

    def send(self, t_ns: int, tau_b: list[float] = TAU) -> None:
        """A generalized force command stamped t_ns, as the controller publishes it."""
        sec, nanosec = divmod(t_ns, 1_000_000_000)
        msg = GeneralizedForce(header=Header(stamp=Time(sec=sec, nanosec=nanosec),
                                             frame_id='base_link_frd'),
                               joint_names=list(JOINTS), joint_torques=tau_b[6:])
        wrench = msg.vehicle_wrench
        wrench.force.x, wrench.force.y, wrench.force.z = tau_b[0:3]
        wrench.torque.x, wrench.torque.y, wrench.torque.z = tau_b[3:6]
        self.commands.publish(msg)

    def exchange(self, t_ns: int) -> ActuatorCommand:
        """Lockstep: send the command stamped t_ns and wait for the answer with that stamp."""
        self.send(t_ns)
        assert self.spin_until(lambda: any(stamp_ns(a) == t_ns for a in self.actuators)), t_ns
        return next(a for a in self.actuators if stamp_ns(a) == t_ns)

    def call(self, srv_type: Any, name: str, request: Any) -> Any:
        """Call a service of the allocator from the probe, as ``ros2 lifecycle`` does."""
        client = self.probe.create_client(srv_type, SERVICE + name)
        try:
            assert client.wait_for_service(timeout_sec=5.0)
            future = client.call_async(request)
            assert self.spin_until(future.done)
            return future.result()
        finally:
            self.probe.destroy_client(client)

    def change_state(self, transition_id: int) -> bool:
        """``ros2 lifecycle set /uvms/thruster_allocator <transition>``: success."""
        request = ChangeState.Request(transition=Transition(id=transition_id))
        return bool(self.call(ChangeState, 'change_state', request).success)

    def get_state(self) -> str:
        """``ros2 lifecycle get /uvms/thruster_allocator``: the state's label."""
        return str(self.call(GetState, 'get_state', GetState.Request()).current_state.label)

    def spin_until(self, done: Callable[[], bool], timeout_s: float = 5.0) -> bool:
        """Spin until done() or the wall-clock timeout."""
        deadline = time.monotonic() + timeout_s
        while not done():
            if time.monotonic() > deadline:
                return False
            self.executor.spin_once(timeout_sec=0.01)
        return True

    def spin_for(self, seconds: float) -> None:
        """Spin for a wall-clock duration."""
        self.spin_until(lambda: False, seconds)

    def close(self) -> None:
        """Destroy the nodes and shut the context down."""
        self.executor.shutdown()
        for node in self.nodes:
            node.destroy_node()
        rclpy.try_shutdown(context=self.context)


@pytest.fixture
def graph() -> Iterator[Graph]:
    """A fresh in-process graph."""
    g = Graph()
    yield g
    g.close()


def test_autostart_brings_the_allocator_to_active(graph: Graph) -> None:
    """By default the node configures and activates itself and answers in lockstep."""
    allocator = graph.allocator()
    assert state_label(allocator) == 'active'
    assert graph.get_state() == 'active'
    for k in range(5):
        graph.exchange(k * PERIOD_NS)
    assert np.any(np.array(graph.actuators[-1].thrust) != 0.0)


def test_deactivation_gives_zero_commands_within_two_control_periods(graph: Graph) -> None:
    """Deactivated in lockstep: zeros at once, and the next commands are answered with zeros."""
    allocator = graph.allocator()
    for k in range(10):
        answer = graph.exchange(k * PERIOD_NS)
    assert np.all(np.abs(answer.thrust) > 0.0)
    assert list(answer.joint_torques) == TAU[6:]
    before = len(graph.actuators)
    assert allocator.trigger_deactivate() == SUCCESS
    # Published inside the transition: no command needed for the first zero.
    assert graph.spin_until(lambda: len(graph.actuators) > before)
    assert is_zero(graph.actuators[before])
    for k in (10, 11):  # the next two control periods
        assert is_zero(graph.exchange(k * PERIOD_NS))
    assert state_label(allocator) == 'inactive'


def test_reactivation_resumes_nonzero_thrust(graph: Graph) -> None:
    """After deactivate and activate the thrusters spin up again from rest on the command."""
    allocator = graph.allocator()
    for k in range(5):
        graph.exchange(k * PERIOD_NS)
    allocator.trigger_deactivate()
    for k in range(5, 10):
        assert is_zero(graph.exchange(k * PERIOD_NS))
    allocator.trigger_activate()
    answers = [graph.exchange(k * PERIOD_NS) for k in range(10, 20)]
    assert list(answers[0].thrust) == [0.0] * 8  # from rest, no elapsed time yet
    assert np.all(np.abs(answers[-1].thrust) > np.abs(answers[1].thrust))
    assert list(answers[-1].joint_torques) == TAU[6:]


def test_an_inactive_allocator_answers_every_lockstep_stamp(graph: Graph) -> None:
    """Each command, whatever its content, gets zeros stamped like it: lockstep never stalls."""
    allocator = graph.allocator(autostart=False)
    assert allocator.trigger_configure() == SUCCESS
    assert state_label(allocator) == 'inactive'
    stamps = [k * PERIOD_NS for k in range(20)]
    for t_ns in stamps:
        assert is_zero(graph.exchange(t_ns))
    assert [stamp_ns(a) for a in graph.actuators] == stamps
    assert all(list(a.joint_names) == list(JOINTS) for a in graph.actuators)


def test_an_inactive_timer_allocator_publishes_zeros_at_its_rate(graph: Graph) -> None:
    """Timer mode, inactive: zero commands at rate_hz of the steady clock, even with input."""
    allocator = graph.allocator(trigger_mode='timer', rate_hz=200.0, use_sim_time=False)
    graph.send(0)
    assert graph.spin_until(lambda: any(not is_zero(a) for a in graph.actuators))
    allocator.trigger_deactivate()
    count = len(graph.actuators)
    graph.spin_for(0.3)
    zeros = graph.actuators[count:]
    assert len(zeros) > 30  # about 60 at 200 Hz
    assert all(is_zero(a) for a in zeros)


def test_autostart_false_leaves_the_allocator_unconfigured(graph: Graph) -> None:
    """Unconfigured: parameters declared, nothing built; lockstep commands get zeros.

    Before issue 29 an unconfigured allocator subscribed nothing and answered nothing, so a
    scenario with ``thruster_allocator: {autostart: false}`` kept ``uvms run`` at t = 0.
    """
    allocator = graph.allocator(autostart=False)
    assert graph.get_state() == 'unconfigured'
    assert allocator.core is None
    assert allocator.has_parameter('rate_hz') and allocator.has_parameter('autostart')
    assert allocator.get_parameter('autostart').value is False
    stamps = [k * PERIOD_NS for k in range(5)]
    for t_ns in stamps:
        assert is_zero(graph.exchange(t_ns))
    assert [stamp_ns(a) for a in graph.actuators] == stamps
    assert all(list(a.joint_names) == list(JOINTS) for a in graph.actuators)


def test_an_unconfigured_timer_allocator_publishes_nothing(graph: Graph) -> None:
    """Timer mode (real time) unconfigured: no command (the simulator holds until active)."""
    graph.allocator(autostart=False, trigger_mode='timer', use_sim_time=False)
    graph.send(0)
    graph.spin_for(0.2)
    assert graph.actuators == []


def test_configure_ends_the_unconfigured_answers(graph: Graph) -> None:
    """Configured (inactive), the node answers once per command, through its own publisher."""
    allocator = graph.allocator(autostart=False)
    assert allocator.trigger_configure() == SUCCESS
    assert allocator.count_publishers('/uvms/command/actuators') == 1
    assert is_zero(graph.exchange(0))
    graph.spin_for(0.1)
    assert len(graph.actuators) == 1


def test_the_lifecycle_services_drive_a_full_cycle(graph: Graph) -> None:
    """change_state as ``ros2 lifecycle set`` sends it: configure .. cleanup and back."""
    graph.allocator(autostart=False)
    steps = [(Transition.TRANSITION_CONFIGURE, 'inactive'),
             (Transition.TRANSITION_ACTIVATE, 'active'),
             (Transition.TRANSITION_DEACTIVATE, 'inactive'),
             (Transition.TRANSITION_CLEANUP, 'unconfigured'),
             (Transition.TRANSITION_CONFIGURE, 'inactive'),
             (Transition.TRANSITION_ACTIVATE, 'active')]
    for transition, label in steps:
        assert graph.change_state(transition), transition
        assert graph.get_state() == label
    for k in range(5):  # entities created by the second configure work on the running executor
        graph.exchange(k * PERIOD_NS)
    assert np.any(np.array(graph.actuators[-1].thrust) != 0.0)
    assert not graph.change_state(Transition.TRANSITION_CONFIGURE)  # not from active
    assert graph.change_state(Transition.TRANSITION_ACTIVE_SHUTDOWN)
    assert graph.get_state() == 'finalized'
    assert is_zero(graph.actuators[-1])  # shutting down from active leaves zero commands


def test_an_invalid_parameter_fails_configure_and_is_logged(
    graph: Graph, capfd: pytest.CaptureFixture[str]
) -> None:
    """Without autostart, configure returns FAILURE, names the parameter, stays unconfigured."""
    graph.allocator(autostart=False, **{'thruster.max_motor_current_a': 5.0})
    assert not graph.change_state(Transition.TRANSITION_CONFIGURE)
    assert graph.get_state() == 'unconfigured'
    assert "configure failed: parameter 'thruster.max_motor_current_a' = 5.0" in (
        capfd.readouterr().err)


def test_an_invalid_parameter_under_autostart_stops_the_node(graph: Graph) -> None:
    """Autostart raises the configure error from the constructor, as before the lifecycle."""
    with pytest.raises(ThrusterParameterError, match=r'allocator\.max_joint_torque_n_m'):
        graph.allocator(**{'allocator.max_joint_torque_n_m': [1.0, 2.0]})


def test_diagnostics_report_the_lifecycle_state(graph: Graph) -> None:
    """'thruster_allocator: allocation' on /diagnostics: OK active, WARN inactive."""
    allocator = graph.allocator(use_sim_time=False)

    def report() -> DiagnosticStatus | None:
        names = {s.name: s for a in graph.diagnostics for s in a.status}
        return names.get('thruster_allocator: allocation')

    for k in range(3):
        graph.exchange(k * PERIOD_NS)
    assert graph.spin_until(lambda: report() is not None, 3.0)
    status = report()
    assert status is not None
    values = {kv.key: kv.value for kv in status.values}
    assert (status.level, status.message, status.hardware_id) == (DiagnosticStatus.OK, 'running',
                                                                  'uvms')
    assert values['lifecycle_state'] == 'active'
    assert values['rejected_commands'] == '0'
    allocator.trigger_deactivate()
    graph.diagnostics.clear()
    assert graph.spin_until(lambda: report() is not None, 3.0)
    status = report()
    assert status is not None
    assert status.level == DiagnosticStatus.WARN
    assert {kv.key: kv.value for kv in status.values}['lifecycle_state'] == 'inactive'


def test_state_ids_match_lifecycle_msgs(graph: Graph) -> None:
    """get_state reports the standard ids, as any lifecycle manager expects."""
    graph.allocator()
    state = graph.call(GetState, 'get_state', GetState.Request()).current_state
    assert (state.id, state.label) == (State.PRIMARY_STATE_ACTIVE, 'active')


def test_desired_output_sends_the_allocated_thrusts_without_the_dynamics(graph: Graph) -> None:
    """thruster_output desired (hardware): the first answer already carries the full thrust."""
    graph.allocator(thruster_output='desired')
    answers = [graph.exchange(k * PERIOD_NS) for k in range(3)]
    assert np.all(np.abs(answers[0].thrust) > 0.0)
    np.testing.assert_allclose(answers[0].thrust, answers[2].thrust)


def test_an_unknown_thruster_output_is_refused_naming_it(graph: Graph) -> None:
    """A typo in thruster_output stops the node at start-up with the name and the choices."""
    with pytest.raises(ThrusterParameterError, match=r"thruster_output.*'actual', 'desired'"):
        graph.allocator(thruster_output='desire')
