"""The simulator node on an executor: rates, lockstep handshake, watchdog, bad input."""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import pytest
import rclpy
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PoseStamped, TwistWithCovarianceStamped, WrenchStamped
from lifecycle_msgs.srv import GetState
from nav_msgs.msg import Odometry
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile
from rclpy.serialization import serialize_message
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool
from tf2_msgs.msg import TFMessage
from uvms_sim.errors import SimParameterError, SimulationError, StartupError
from uvms_sim.simulator_node import SimulatorNode

from uvms_msgs.msg import ActuatorCommand, ContactState, GeneralizedForce

N_THRUSTERS = 8


def stamp_ns(msg: Any) -> int:
    """Header stamp of a message (ns)."""
    return msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec


@dataclass
class Responder:
    """Test stand-in for controller + allocator: answers each state with a command.

    Attributes:
        node: The test node in /uvms.
        torques: Joint torques to command (N*m).
        answer: Decides per state stamp (ns) whether to answer it.
        states: Joint states received, in order.
    """

    node: Node
    torques: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    answer: Callable[[int], bool] = lambda _: True
    states: list[JointState] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.publisher = self.node.create_publisher(ActuatorCommand, 'command/actuators', 10)
        self.node.create_subscription(JointState, 'joint_states', self._on_state, 100)

    def _on_state(self, msg: JointState) -> None:
        self.states.append(msg)
        if self.answer(stamp_ns(msg)):
            self.send(stamp_ns(msg))

    def send(self, t_ns: int, thrust: list[float] | None = None,
             torques: list[float] | None = None) -> None:
        """Publish a command stamped t_ns."""
        msg = ActuatorCommand(thrust=thrust if thrust is not None else [0.0] * N_THRUSTERS,
                              joint_torques=torques if torques is not None else self.torques)
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(t_ns, 1_000_000_000)
        self.publisher.publish(msg)


@dataclass
class Harness:
    """A simulator, a responder and an executor in their own context."""

    context: Context
    executor: SingleThreadedExecutor
    responder: Responder
    make_simulator: Callable[..., SimulatorNode]
    simulator: SimulatorNode | None = None

    def start(self, **parameters: Any) -> SimulatorNode:
        """Build the simulator with parameter overrides and add it to the executor."""
        self.simulator = self.make_simulator(**parameters)
        self.executor.add_node(self.simulator)
        return self.simulator

    def spin_until(self, done: Callable[[], bool], timeout_s: float = 10.0) -> None:
        """Spin until done() or the timeout (wall clock) fails the test."""
        deadline = time.monotonic() + timeout_s
        while not done():
            assert time.monotonic() < deadline, 'timed out spinning'
            self.executor.spin_once(timeout_sec=0.05)

    def spin_for(self, seconds: float) -> None:
        """Spin for a wall-clock time."""
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.01)


@pytest.fixture
def harness() -> Iterator[Harness]:
    """Fresh context with a responder node; the test starts the simulator."""
    context = Context()
    rclpy.init(args=[], context=context)
    executor = SingleThreadedExecutor(context=context)
    responder = Responder(rclpy.create_node('responder', namespace='uvms', context=context))
    executor.add_node(responder.node)
    made: list[SimulatorNode] = []

    def make(**parameters: Any) -> SimulatorNode:
        overrides = [Parameter(name.replace('__', '.'), value=value)
                     for name, value in parameters.items()]
        node = SimulatorNode(namespace='uvms', context=context, parameter_overrides=overrides)
        made.append(node)
        return node

    yield Harness(context, executor, responder, make)
    executor.shutdown()
    for node in [*made, responder.node]:
        node.destroy_node()
    rclpy.try_shutdown(context=context)


def collect(harness: Harness, msg_type: Any, topic: str, qos: Any = 100) -> list[Any]:
    """Subscribe the responder node to a topic and return the list it fills."""
    received: list[Any] = []
    harness.responder.node.create_subscription(msg_type, topic, received.append, qos)
    return received


def test_state_topics_publish_every_second_physics_step(harness: Harness) -> None:
    """At 1 kHz physics the state and /clock come every 2 ms of simulated time (500 Hz)."""
    topics = {name: collect(harness, msg_type, name) for name, msg_type in [
        ('odometry', Odometry), ('wrench', WrenchStamped), ('ee_pose', PoseStamped),
        ('contact', ContactState)]}
    clocks = collect(harness, Clock, '/clock')
    sim = harness.start(duration_s=0.02)
    harness.spin_until(lambda: sim.finished)
    expected = [2_000_000 * k for k in range(11)]
    assert [stamp_ns(m) for m in harness.responder.states] == expected
    for name, received in topics.items():
        assert [stamp_ns(m) for m in received] == expected, name
    assert [c.clock.sec * 10**9 + c.clock.nanosec for c in clocks] == expected


def test_publish_rate_parameter_sets_the_control_rate(harness: Harness) -> None:
    """publish_rate_hz = 250 publishes every fourth step of the 1 kHz simulation."""
    sim = harness.start(duration_s=0.02, publish_rate_hz=250.0)
    harness.spin_until(lambda: sim.finished)
    assert [stamp_ns(m) for m in harness.responder.states] == [4_000_000 * k for k in range(6)]


def test_lockstep_simulator_waits_for_the_command_of_its_step(harness: Harness) -> None:
    """No new state is published until the command stamped like the last state arrives."""
    held = 10_000_000
    harness.responder.answer = lambda t_ns: t_ns != held
    sim = harness.start()
    harness.spin_until(lambda: sim.sim_time_ns == held)
    harness.spin_for(0.2)
    assert stamp_ns(harness.responder.states[-1]) == held
    assert sim.sim_time_ns == held
    harness.responder.send(held - 2_000_000)  # an older command does not count
    harness.spin_for(0.1)
    assert sim.sim_time_ns == held
    harness.responder.send(held)
    harness.spin_until(lambda: sim.sim_time_ns > held)
    assert sim.timeouts == 0


def test_lockstep_timeout_steps_with_last_command(harness: Harness) -> None:
    """Without the command of its step the simulator steps after the wall-clock timeout."""
    harness.responder.answer = lambda t_ns: t_ns < 4_000_000
    sim = harness.start(lockstep_timeout_s=0.05)
    harness.spin_until(lambda: sim.sim_time_ns >= 10_000_000)
    assert sim.timeouts >= 3


def test_simulator_offers_first_state_until_a_command_arrives(harness: Harness) -> None:
    """Before any command it re-publishes the initial state instead of stepping."""
    harness.responder.answer = lambda _: False
    sim = harness.start(lockstep_timeout_s=0.02)
    harness.spin_until(lambda: len(harness.responder.states) >= 3)
    assert sim.sim_time_ns == 0
    assert {stamp_ns(m) for m in harness.responder.states} == {0}


def test_stale_command_sets_motor_torques_to_zero(
    harness: Harness, capfd: pytest.CaptureFixture[str]
) -> None:
    """A command older than watchdog_timeout_s (simulated) is replaced by zeros, logged once."""
    harness.responder.torques = [1.0, 2.0, 3.0]
    harness.responder.answer = lambda t_ns: t_ns == 0
    harness.start(lockstep_timeout_s=0.01, watchdog_timeout_s=0.005)
    harness.spin_until(lambda: any(stamp_ns(m) >= 16_000_000 for m in harness.responder.states))
    efforts = {stamp_ns(m): list(m.effort) for m in harness.responder.states}
    assert efforts[2_000_000] == [1.0, 2.0, 3.0]
    assert efforts[16_000_000] == [0.0, 0.0, 0.0]
    assert capfd.readouterr().err.count('set to zero') == 1


@pytest.mark.parametrize(
    ('thrust', 'torques', 'expected'),
    [
        ([0.0] * N_THRUSTERS, [0.0, math.nan, 0.0], 'non-finite'),
        ([0.0] * N_THRUSTERS, [math.inf, 0.0, 0.0], 'non-finite'),
        ([0.0] * (N_THRUSTERS - 1), [0.0] * 3, 'thrust has 7 values'),
        ([0.0] * N_THRUSTERS, [0.0] * 4, 'joint_torques has 4 values'),
    ],
)
def test_bad_actuator_command_is_rejected_and_logged(
    harness: Harness,
    capfd: pytest.CaptureFixture[str],
    thrust: list[float],
    torques: list[float],
    expected: str,
) -> None:
    """A NaN/Inf or wrongly sized command is logged as an error and never moves the state."""
    harness.responder.answer = lambda _: False
    sim = harness.start(lockstep_timeout_s=60.0)
    harness.spin_until(lambda: len(harness.responder.states) == 1)
    harness.responder.send(0, thrust=thrust, torques=torques)
    harness.spin_for(0.1)
    assert sim.sim_time_ns == 0
    err = capfd.readouterr().err
    assert 'rejected actuator command' in err
    assert expected in err
    harness.responder.send(0)
    harness.spin_until(lambda: sim.sim_time_ns == 2_000_000)


def test_joint_states_carry_arm_joints_and_applied_torques(harness: Harness) -> None:
    """joint_states names the three arm joints and reports the applied torques as effort."""
    harness.responder.torques = [0.5, -0.5, 0.25]
    sim = harness.start(duration_s=0.004)
    harness.spin_until(lambda: sim.finished)
    last = harness.responder.states[-1]
    assert list(last.name) == ['joint_1', 'joint_2', 'joint_3']
    assert list(last.effort) == [0.5, -0.5, 0.25]
    assert len(last.position) == len(last.velocity) == 3


def test_frames_of_the_state_topics(harness: Harness) -> None:
    """Odometry map_ned -> base_link_frd, wrench in ft_sensor_link, ee_pose in map_ned."""
    odometry = collect(harness, Odometry, 'odometry')
    wrench = collect(harness, WrenchStamped, 'wrench')
    ee_pose = collect(harness, PoseStamped, 'ee_pose')
    sim = harness.start(duration_s=0.002)
    harness.spin_until(lambda: sim.finished)
    assert (odometry[0].header.frame_id, odometry[0].child_frame_id) == ('map_ned',
                                                                         'base_link_frd')
    assert wrench[0].header.frame_id == 'ft_sensor_link'
    assert ee_pose[0].header.frame_id == 'map_ned'
    position = ee_pose[0].pose.position
    assert (position.x, position.y, position.z) == pytest.approx((1.7, 0.0, -0.1), abs=1e-8)


def test_static_tf_reaches_late_subscriber(harness: Harness) -> None:
    """/tf_static is transient local: a subscriber created later still gets the twins."""
    sim = harness.start(duration_s=0.002)
    harness.spin_until(lambda: sim.finished)
    latched = collect(harness, TFMessage, '/tf_static', QoSProfile(
        depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL))
    harness.spin_until(lambda: bool(latched))
    pairs = {(t.header.frame_id, t.child_frame_id) for t in latched[0].transforms}
    assert {('map', 'map_ned'), ('base_link_frd', 'base_link')} <= pairs


def test_dvl_frame_is_on_tf_static_at_the_robots_mounting(harness: Harness) -> None:
    """With navigation on, each dvl message's frame resolves: base_link_frd -> dvl_link.

    The mounting is the robot's navigation.yaml (BlueROV2: navigation.dvl.position_m
    [-0.1, 0.0, 0.15] m, axes along base_link_frd).
    """
    harness.responder.torques = [0.0] * 4  # the Alpha 5's four joints
    dvl = collect(harness, TwistWithCovarianceStamped, 'dvl')
    sim = harness.start(robot_name='bluerov2_alpha5', navigation__enabled=True,
                        world__seabed_depth_m=2.0, duration_s=0.2)
    harness.spin_until(lambda: sim.finished and bool(dvl))
    latched = collect(harness, TFMessage, '/tf_static', QoSProfile(
        depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL))
    harness.spin_until(lambda: bool(latched))
    by_child = {t.child_frame_id: t for t in latched[0].transforms}
    assert {msg.header.frame_id for msg in dvl} == {'dvl_link'}
    mount = by_child['dvl_link']
    assert mount.header.frame_id == 'base_link_frd'
    t = mount.transform
    assert (t.translation.x, t.translation.y, t.translation.z) == pytest.approx(
        (-0.1, 0.0, 0.15), abs=1e-12)
    assert (t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w) == pytest.approx(
        (0.0, 0.0, 0.0, 1.0), abs=1e-12)


def test_tf_is_published_at_its_own_rate(harness: Harness) -> None:
    """/tf comes every 10th state at tf_rate_hz = 50 (500 Hz states)."""
    tf = collect(harness, TFMessage, '/tf')
    sim = harness.start(duration_s=0.04)
    harness.spin_until(lambda: sim.finished)
    assert [t.transforms[0].header.stamp.nanosec for t in tf] == [0, 20_000_000, 40_000_000]


def test_ground_truth_topics_at_their_own_rate(harness: Harness) -> None:
    """ground_truth_rate_hz = 100: ee_pose and contact every 5th state, the sensors every one."""
    slow = {name: collect(harness, msg_type, name) for name, msg_type in [
        ('ee_pose', PoseStamped), ('contact', ContactState)]}
    wrench = collect(harness, WrenchStamped, 'wrench')
    sim = harness.start(duration_s=0.02, ground_truth_rate_hz=100.0)
    harness.spin_until(lambda: sim.finished)
    for name, received in slow.items():
        assert [stamp_ns(m) for m in received] == [0, 10_000_000, 20_000_000], name
    assert [stamp_ns(m) for m in wrench] == [2_000_000 * k for k in range(11)]


def test_invalid_parameter_stops_start_up_naming_it(harness: Harness) -> None:
    """An out-of-range parameter raises at construction with name, value and range."""
    with pytest.raises(SimParameterError) as info:
        harness.start(physics_rate_hz=-1.0)
    assert 'physics_rate_hz' in str(info.value)
    assert '-1.0' in str(info.value)


def test_invalid_robot_parameter_stops_start_up_naming_it(harness: Harness) -> None:
    """A robot parameter outside its range stops the simulator naming it."""
    with pytest.raises(SimParameterError, match=r'contact\.stiffness_n_m'):
        harness.start(contact__stiffness_n_m=-5.0)


def test_simulator_refuses_sim_time(harness: Harness) -> None:
    """The clock source cannot run on /clock itself."""
    with pytest.raises(SimParameterError, match='use_sim_time'):
        harness.start(use_sim_time=True)


def test_diverging_simulation_stops_with_its_cause(harness: Harness) -> None:
    """Absurd motor torques make the state diverge: spinning raises, naming the cause."""
    harness.responder.torques = [0.0, 0.0, 1.0e6]
    harness.start()
    with pytest.raises(SimulationError, match='state diverged'):
        harness.spin_for(5.0)


def test_realtime_mode_steps_on_the_wall_clock(harness: Harness) -> None:
    """In real time the simulator steps on its own timer and publishes every 2 ms."""
    harness.responder.answer = lambda _: False
    sim = harness.start(mode='realtime', duration_s=0.05, startup__hold=False)
    start = time.monotonic()
    harness.spin_until(lambda: sim.finished and len(harness.responder.states) >= 26)
    assert time.monotonic() - start >= 0.05
    harness.spin_for(0.05)
    assert sim.sim_time_ns == 50_000_000
    stamps = [stamp_ns(m) for m in harness.responder.states]
    assert stamps == [2_000_000 * k for k in range(26)]


def simulation_status(arrays: list[DiagnosticArray]) -> tuple[DiagnosticStatus, dict[str, str]]:
    """The simulator's status in the last array, and its values by key."""
    [status] = [s for s in arrays[-1].status if s.name == 'simulator: simulation']
    return status, {kv.key: kv.value for kv in status.values}


def test_diagnostics_report_step_rate_and_real_time_factor(harness: Harness) -> None:
    """Lockstep answered at once: OK, steps per wall second = 1000 x the real-time factor."""
    arrays = collect(harness, DiagnosticArray, '/diagnostics', 10)
    harness.start()
    harness.spin_until(lambda: len(arrays) >= 2, timeout_s=5.0)
    status, values = simulation_status(arrays)
    assert (status.level, status.message, status.hardware_id) == (
        DiagnosticStatus.OK, 'running', 'uvms')
    assert values['mode'] == 'lockstep' and values['lockstep_timeouts'] == '0'
    step_hz, factor = float(values['step_rate_hz']), float(values['real_time_factor'])
    assert step_hz > 10.0
    assert step_hz == pytest.approx(1000.0 * factor, rel=2e-3)  # 1 kHz physics


def test_lockstep_timeouts_are_reported_as_a_warning(harness: Harness) -> None:
    """Unanswered states: WARN naming the timeouts, with their count."""
    arrays = collect(harness, DiagnosticArray, '/diagnostics', 10)
    harness.responder.answer = lambda t_ns: t_ns < 4_000_000
    sim = harness.start(lockstep_timeout_s=0.05)
    harness.spin_until(lambda: len(arrays) >= 2, timeout_s=5.0)
    status, values = simulation_status(arrays)
    assert status.level == DiagnosticStatus.WARN
    assert status.message == 'lockstep timeouts: stepping on the last command'
    assert 0 < int(values['lockstep_timeouts']) <= sim.timeouts


@pytest.mark.parametrize(('robot', 'ee_position'), [
    ('paper_uvms', [1.70, 0.0, -0.10]),
    ('bluerov2_alpha5', [0.37, 0.0, -0.07]),
])
def test_robot_starts_at_its_default_start_when_none_is_given(
    harness: Harness, robot: str, ee_position: list[float]
) -> None:
    """No initial.* given: the parameters and the first ee_pose are the robot's start.yaml."""
    poses = collect(harness, PoseStamped, 'ee_pose')
    simulator = harness.start(robot_name=robot)
    assert list(simulator.get_parameter('initial.ee_position').value) == ee_position
    harness.spin_until(lambda: len(poses) > 0)
    position = poses[0].pose.position
    assert [position.x, position.y, position.z] == pytest.approx(ee_position, abs=1e-6)


def test_out_of_reach_start_names_robot_residual_and_default(harness: Harness) -> None:
    """The paper's point A given to the BlueROV2: robot, residual and its own start named."""
    with pytest.raises(SimParameterError) as info:
        harness.start(robot_name='bluerov2_alpha5', initial__ee_position=[1.7, 0.0, -0.1])
    message = str(info.value)
    assert message.startswith("robot 'bluerov2_alpha5': parameter 'initial.ee_position'")
    assert 'residual 1.4' in message
    assert 'initial.ee_position = [0.37, 0.0, -0.07]' in message


def relay_generalized_force(harness: Harness) -> list[int]:
    """Make the responder also answer each state with a generalized force (a controller)."""
    node = harness.responder.node
    publisher = node.create_publisher(GeneralizedForce, 'command/generalized_force', 10)
    relayed: list[int] = []

    def relay(msg: JointState) -> None:
        command = GeneralizedForce(joint_names=list(msg.name), joint_torques=[0.0] * 3)
        command.header.stamp = msg.header.stamp
        publisher.publish(command)
        relayed.append(stamp_ns(msg))

    node.create_subscription(JointState, 'joint_states', relay, 10)
    return relayed


def test_lockstep_start_up_timeout_names_the_controller(harness: Harness) -> None:
    """Nothing answers the initial state: after startup.timeout_s an error names the controller.

    Before issue 29 the simulator re-offered the initial state forever.
    """
    harness.responder.answer = lambda _: False
    sim = harness.start(startup__timeout_s=1.0, lockstep_timeout_s=0.2)
    with pytest.raises(StartupError, match='the controller did not answer'):
        harness.spin_for(15.0)
    assert sim.sim_time_ns == 0


def test_lockstep_start_up_timeout_names_the_allocator(harness: Harness) -> None:
    """The controller answers but no actuator command comes: the error names the allocator."""
    harness.responder.answer = lambda _: False
    relayed = relay_generalized_force(harness)
    harness.start(startup__timeout_s=1.0, lockstep_timeout_s=0.2)
    with pytest.raises(StartupError, match='the thruster_allocator did not answer'):
        harness.spin_for(15.0)
    assert relayed and set(relayed) == {0}


def test_realtime_simulator_holds_the_initial_state_until_the_loop_closes(
    harness: Harness,
) -> None:
    """Real time: while no managed node is active, time stands still at t_0, re-offered.

    Before issue 29 physics integrated from the first tick with zero commands.
    """
    harness.responder.answer = lambda _: False
    relay_generalized_force(harness)
    clocks = collect(harness, Clock, '/clock')
    sim = harness.start(mode='realtime', startup__nodes=['controller'], startup__timeout_s=0.0)
    harness.spin_for(1.0)
    harness.responder.send(0)
    harness.spin_for(0.5)
    assert sim.sim_time_ns == 0
    assert len(harness.responder.states) >= 5  # the held state, re-offered
    assert {stamp_ns(m) for m in harness.responder.states} == {0}
    assert clocks and {c.clock.sec * 10**9 + c.clock.nanosec for c in clocks} == {0}


@pytest.mark.parametrize('mode', ['lockstep', 'realtime'])
def test_first_state_waits_for_the_recorder_to_subscribe(harness: Harness, mode: str) -> None:
    """startup.recorder: nothing goes out before that node subscribes; its record starts at 0.

    What ``uvms launch --output`` relies on: a recorder process that starts after the
    simulator still records the run from t = 0.
    """
    overrides: dict[str, Any] = {'mode': mode, 'startup__recorder': 'recorder',
                                 'duration_s': 0.02}
    if mode == 'realtime':
        overrides['startup__hold'] = False  # no managed nodes here: the recorder alone holds
    sim = harness.start(**overrides)
    harness.spin_for(1.0)
    assert harness.responder.states == []
    assert sim.sim_time_ns == 0
    recorder = rclpy.create_node('recorder', namespace='uvms', context=harness.context)
    received: dict[str, list[Any]] = {}
    for topic, msg_type in [('/clock', Clock), ('joint_states', JointState),
                            ('odometry', Odometry), ('wrench', WrenchStamped),
                            ('ee_pose', PoseStamped), ('contact', ContactState)]:
        received[topic] = []
        recorder.create_subscription(msg_type, topic, received[topic].append, 100)
    harness.executor.add_node(recorder)
    try:
        harness.spin_until(lambda: sim.finished and bool(received['contact']))
    finally:
        harness.executor.remove_node(recorder)
        recorder.destroy_node()
    assert received['/clock'][0].clock.sec == received['/clock'][0].clock.nanosec == 0
    for topic in ('joint_states', 'odometry', 'wrench', 'ee_pose', 'contact'):
        assert stamp_ns(received[topic][0]) == 0, topic


def test_a_recorder_of_fewer_topics_is_waited_for_on_those_only(harness: Harness) -> None:
    """startup.recorder_topics: a recorder of /clock and joint_states alone starts the run.

    A scenario that gives the recorder fewer topics (``uvms identify plan``'s) held the
    simulator at t = 0 until ``startup.timeout_s``: it waited on every state topic.
    """
    sim = harness.start(mode='lockstep', startup__recorder='recorder', duration_s=0.02,
                        startup__recorder_topics=['/clock', 'joint_states'])
    harness.spin_for(0.5)
    assert sim.sim_time_ns == 0
    recorder = rclpy.create_node('recorder', namespace='uvms', context=harness.context)
    received: dict[str, list[Any]] = {'/clock': [], 'joint_states': []}
    recorder.create_subscription(Clock, '/clock', received['/clock'].append, 100)
    recorder.create_subscription(JointState, 'joint_states', received['joint_states'].append,
                                 100)
    harness.executor.add_node(recorder)
    try:
        harness.spin_until(lambda: sim.finished)
    finally:
        harness.executor.remove_node(recorder)
        recorder.destroy_node()
    assert received['/clock'][0].clock.sec == received['/clock'][0].clock.nanosec == 0
    assert stamp_ns(received['joint_states'][0]) == 0


def mission_says_ready(harness: Harness) -> Node:
    """A node named mission publishing True on mission/ready, latched as the mission does."""
    mission = rclpy.create_node('mission', namespace='uvms', context=harness.context)
    mission.create_publisher(Bool, 'mission/ready', QoSProfile(
        depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)).publish(Bool(data=True))
    return mission


@pytest.mark.parametrize('mode', ['lockstep', 'realtime'])
def test_first_state_waits_for_the_mission_to_be_ready(harness: Harness, mode: str) -> None:
    """startup.mission: no state (and no simulated time) before the mission says it is ready.

    What ``uvms launch`` of a scenario with a mission relies on: a mission still discovering
    the controller's action server cannot start its goals late, physics waits for it.
    """
    overrides: dict[str, Any] = {'mode': mode, 'startup__mission': 'mission/ready',
                                 'duration_s': 0.02}
    if mode == 'realtime':
        overrides['startup__hold'] = False  # no managed nodes here: the mission alone holds
    sim = harness.start(**overrides)
    harness.spin_for(1.0)
    assert harness.responder.states == []
    assert sim.sim_time_ns == 0
    mission = mission_says_ready(harness)
    try:
        harness.spin_until(lambda: sim.finished)
    finally:
        mission.destroy_node()
    assert harness.responder.states and stamp_ns(harness.responder.states[0]) == 0


def test_realtime_hold_publishes_the_held_state_and_waits_for_the_mission(
        harness: Harness) -> None:
    """Real time with the hold: the state goes out at once, physics waits for the mission.

    With ``--hardware twin`` the twins answer the bridges only once the plant has a state:
    a first state held back for the mission made a slow mission fail the bridges' start.
    """
    relay_generalized_force(harness)
    controller = rclpy.create_node('controller', namespace='uvms', context=harness.context)

    def active(_: GetState.Request, response: GetState.Response) -> GetState.Response:
        response.current_state.label = 'active'
        return response

    controller.create_service(GetState, 'controller/get_state', active)
    harness.executor.add_node(controller)
    sim = harness.start(mode='realtime', startup__nodes=['controller'], startup__timeout_s=0.0,
                        startup__mission='mission/ready', duration_s=0.02)
    harness.spin_for(1.5)  # the loop answers the held state; the mission is not ready
    assert harness.responder.states
    assert {stamp_ns(m) for m in harness.responder.states} == {0}
    assert sim.sim_time_ns == 0
    mission = mission_says_ready(harness)
    try:
        harness.spin_until(lambda: sim.finished)
    finally:
        mission.destroy_node()
        harness.executor.remove_node(controller)
        controller.destroy_node()


def test_a_mission_never_ready_stops_the_start_naming_the_topic(harness: Harness) -> None:
    """After startup.timeout_s without mission/ready, the error names the topic and why."""
    harness.start(startup__mission='mission/ready', startup__timeout_s=0.5)
    with pytest.raises(StartupError, match=r'mission did not say it is ready .* mission/ready'):
        harness.spin_for(2.0)


def test_a_recorder_that_never_subscribes_stops_the_start_naming_it(harness: Harness) -> None:
    """After startup.timeout_s without the recorder, the error names it and the topics."""
    harness.start(startup__recorder='recorder', startup__timeout_s=0.5)
    with pytest.raises(StartupError, match=r'recorder did not subscribe .* /clock'):
        harness.spin_for(2.0)


def test_realtime_start_up_timeout_names_the_inactive_node(harness: Harness) -> None:
    """Real time: a managed node that never reports active is named when the start-up ends."""
    harness.responder.answer = lambda _: False
    harness.start(mode='realtime', startup__nodes=['controller'], startup__timeout_s=1.0)
    with pytest.raises(StartupError, match=r'controller is .*\(not active\)'):
        harness.spin_for(15.0)


def test_a_simulator_process_that_could_not_run_does_not_time_out(harness: Harness) -> None:
    """The executor blocked 2 s (a starved process) while the answer comes: no timeout.

    Issue 29: under load the lockstep timeout (wall clock) fired while the answer was queued
    behind other work of the same process, and the run stepped on an old command.
    """
    def answer_late(t_ns: int) -> bool:
        if t_ns == 2_000_000:
            time.sleep(2.0)  # blocks the one executor thread, the simulator's timer included
        return True

    harness.responder.answer = answer_late
    sim = harness.start(lockstep_timeout_s=1.0, duration_s=0.01)
    harness.spin_until(lambda: sim.finished, timeout_s=20.0)
    assert sim.timeouts == 0


def test_malformed_command_payloads_are_counted_and_survived(
    harness: Harness, capfd: pytest.CaptureFixture[str]
) -> None:
    """Raw garbage on command/actuators: logged once, counted on /diagnostics, run goes on."""
    arrays = collect(harness, DiagnosticArray, '/diagnostics', 10)
    harness.responder.answer = lambda _: False
    sim = harness.start(lockstep_timeout_s=60.0)
    harness.spin_until(lambda: len(harness.responder.states) == 1)
    valid = ActuatorCommand(thrust=[0.0] * N_THRUSTERS, joint_torques=[0.0] * 3)
    good = serialize_message(valid)
    garbage = [b'', good[:-5], b'\x7f\x7f' + good[2:], bytes(range(256))]
    for payload in garbage:
        harness.responder.publisher.publish(payload)
    harness.spin_for(0.2)
    assert sim.sim_time_ns == 0
    harness.responder.send(0)
    harness.spin_until(lambda: sim.sim_time_ns == 2_000_000)
    harness.spin_until(lambda: any(
        simulation_status([a])[1].get('malformed_commands') == str(len(garbage))
        for a in arrays), timeout_s=5.0)
    assert capfd.readouterr().err.count('malformed actuator command payloads') == 1
