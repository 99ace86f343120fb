"""The least genuine rclpy can cost for the lockstep graph's message flow, with no work in it.

``bench_graph.py`` splits a lockstep run into our cores, our glue and the middleware. This
bench measures the middleware alone: stand-in nodes with the graph's names, topics, types,
QoS and lockstep chain, whose callbacks only publish the next prebuilt message, in one
process and one executor as ``uvms run`` spins them:

    simulator  -- /clock, joint_states, odometry, wrench, ee_pose, contact (+ /tf every 10)
    controller -- on the 3 inputs of one stamp: command/generalized_force, controller/state
    allocator  -- on the command: command/actuators, thrusters/state
    simulator  -- on the actuator command: the next state (2 ms later)

plus a visualizer (raw subscriptions to contact and controller/state, an empty MarkerArray
on markers every 10th period: 20 Hz of simulated time, as the real one), a raw subscriber
to every topic standing in for the recorder (it keeps nothing), and
``use_sim_time`` on controller, allocator and recorder (each then subscribes ``/clock``,
as the real nodes do). Messages carry the real sizes (3 joints, 8 thrusters). Two flavours,
run in alternating pairs and printed side by side: ``typed`` (message objects published and
taken, the graph before issue 29) and ``raw`` (the hot topics published as pre-serialized
CDR bytes whose stamp is written in place, and taken with ``raw=True``, as the nodes now do
through ``uvms_common.cdr_codecs``; /tf and rclpy's own /clock subscriptions stay typed).
The figure is
the wall time per control period, and the same for the real graph scaled to it: the
floor per period divided by the plain loop's per-period cost is the lowest
graph / plain-loop ratio any node code could reach on this runtime (bench_graph's
"graph / plain loop", target <= 1.5).

Usage::

    .venv/bin/python bench/bench_middleware_floor.py [--periods N] [--executor KIND]
        [--no-recorder] [--pairs N]
"""

from __future__ import annotations

import argparse
import os
import random
import sys
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / 'src' / 'uvms_common'))

import rclpy  # noqa: E402
from builtin_interfaces.msg import Time  # noqa: E402
from geometry_msgs.msg import PoseStamped, TransformStamped, WrenchStamped  # noqa: E402
from nav_msgs.msg import Odometry  # noqa: E402
from rclpy.context import Context  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.parameter import Parameter  # noqa: E402
from rclpy.qos import QoSProfile, ReliabilityPolicy  # noqa: E402
from rclpy.serialization import serialize_message  # noqa: E402
from rclpy.signals import SignalHandlerOptions  # noqa: E402
from rosgraph_msgs.msg import Clock  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402
from tf2_msgs.msg import TFMessage  # noqa: E402
from uvms_common.cdr_codecs import read_stamp_ns, write_stamp  # noqa: E402
from uvms_common.node_main import make_executor  # noqa: E402
from uvms_common.ros_environment import ros_environment_defaults  # noqa: E402
from uvms_model.description import load_description  # noqa: E402
from visualization_msgs.msg import MarkerArray  # noqa: E402

from uvms_msgs.msg import (  # noqa: E402
    ActuatorCommand,
    ContactState,
    ControllerState,
    GeneralizedForce,
    ThrusterState,
)

#: As the nodes create them (simulator_node.py, controller_node.py, ...).
RELIABLE = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
PERIOD_NS = 2_000_000
TF_EVERY = 10
#: The paper robot's arm joints, read from its URDF (the message sizes of a real run).
JOINTS = list(load_description().joint_names)
THRUSTERS = 8
#: Away from the test suite's ROS_DOMAIN_IDs (0, 1-100, 150-199).
DOMAINS = (101, 149)


def _stamp(t_ns: int) -> Time:
    sec, nanosec = divmod(t_ns, 1_000_000_000)
    return Time(sec=sec, nanosec=nanosec)


def _stamp_ns(msg: Any) -> int:
    """Stamp (ns) of a typed message or of a raw payload (header.stamp right after CDR's 4)."""
    if isinstance(msg, bytes):
        return read_stamp_ns(msg)
    return int(msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec)


class Outgoing:
    """One prebuilt message: published typed with a new stamp, or as its CDR bytes."""

    def __init__(self, msg: Any, raw: bool) -> None:
        self.msg = msg
        self.raw = raw
        self.buffer = bytearray(serialize_message(msg))

    def stamped(self, t_ns: int) -> Any:
        """The message (or payload) stamped t_ns, ready to publish."""
        if self.raw:
            write_stamp(self.buffer, t_ns)
            return bytes(self.buffer)
        if hasattr(self.msg, 'clock'):
            self.msg.clock = _stamp(t_ns)
        else:
            self.msg.header.stamp = _stamp(t_ns)
        return self.msg


class FloorSimulator(Node):
    """Publishes one state per actuator command, 2 ms after the last; the caller starts it."""

    def __init__(self, context: Context, periods: int, raw: bool) -> None:
        super().__init__('simulator', namespace='/uvms', context=context)
        self.periods = periods
        self.done = 0
        self.t_ns = 0
        self._clock_pub = self.create_publisher(Clock, '/clock', RELIABLE)
        self._joints = self.create_publisher(JointState, 'joint_states', RELIABLE)
        self._odom = self.create_publisher(Odometry, 'odometry', RELIABLE)
        self._wrench = self.create_publisher(WrenchStamped, 'wrench', RELIABLE)
        self._ee = self.create_publisher(PoseStamped, 'ee_pose', RELIABLE)
        self._contact = self.create_publisher(ContactState, 'contact', RELIABLE)
        self._tf = self.create_publisher(TFMessage, '/tf', QoSProfile(depth=100))
        self.create_subscription(ActuatorCommand, 'command/actuators', self._on_command,
                                 RELIABLE, raw=raw)
        msgs: dict[str, Any] = {
            'joints': JointState(name=JOINTS, position=[0.1] * 3, velocity=[0.2] * 3,
                                 effort=[0.3] * 3),
            'odom': Odometry(child_frame_id='base_link_frd'),
            'wrench': WrenchStamped(),
            'ee': PoseStamped(),
            'contact': ContactState(),
        }
        msgs['odom'].header.frame_id = 'map_ned'
        self._msgs = {key: Outgoing(msg, raw) for key, msg in msgs.items()}
        self._clock_msg = Outgoing(Clock(), raw)
        self._tf_msg = TFMessage(transforms=[TransformStamped() for _ in range(6)])

    def publish_state(self) -> None:
        """Publish the state messages of ``t_ns``, as the simulator does each state."""
        stamp = _stamp(self.t_ns)
        self._clock_pub.publish(self._clock_msg.stamped(self.t_ns))
        for key, pub in (('joints', self._joints), ('odom', self._odom),
                         ('wrench', self._wrench), ('ee', self._ee),
                         ('contact', self._contact)):
            pub.publish(self._msgs[key].stamped(self.t_ns))
        if (self.t_ns // PERIOD_NS) % TF_EVERY == 0:
            for transform in self._tf_msg.transforms:
                transform.header.stamp = stamp
            self._tf.publish(self._tf_msg)

    def _on_command(self, msg: Any) -> None:
        if _stamp_ns(msg) != self.t_ns:
            return
        self.done += 1
        self.t_ns += PERIOD_NS
        if self.done < self.periods:
            self.publish_state()


class FloorController(Node):
    """On the three inputs of one stamp: one command and one state message."""

    def __init__(self, context: Context, raw: bool) -> None:
        super().__init__('controller', namespace='/uvms', context=context,
                         parameter_overrides=[Parameter('use_sim_time', value=True)])
        self._command = self.create_publisher(GeneralizedForce, 'command/generalized_force',
                                              RELIABLE)
        self._state = self.create_publisher(ControllerState, 'controller/state', RELIABLE)
        self._command_msg = Outgoing(
            GeneralizedForce(joint_names=JOINTS, joint_torques=[0.0] * 3), raw)
        self._state_msg = Outgoing(ControllerState(), raw)
        self._arrived: dict[int, int] = {}
        for msg_type, topic in ((JointState, 'joint_states'), (Odometry, 'odometry'),
                                (WrenchStamped, 'wrench')):
            self.create_subscription(msg_type, topic, self._on_input, RELIABLE, raw=raw)

    def _on_input(self, msg: Any) -> None:
        key = _stamp_ns(msg)
        count = self._arrived.get(key, 0) + 1
        if count < 3:
            self._arrived[key] = count
            return
        del self._arrived[key]
        self._command.publish(self._command_msg.stamped(key))
        self._state.publish(self._state_msg.stamped(key))


class FloorAllocator(Node):
    """On each generalized force: one actuator command and one thruster state."""

    def __init__(self, context: Context, raw: bool) -> None:
        super().__init__('thruster_allocator', namespace='/uvms', context=context,
                         parameter_overrides=[Parameter('use_sim_time', value=True)])
        self._actuators = self.create_publisher(ActuatorCommand, 'command/actuators', RELIABLE)
        self._state = self.create_publisher(ThrusterState, 'thrusters/state', RELIABLE)
        self._actuator_msg = Outgoing(ActuatorCommand(
            thrust=[0.0] * THRUSTERS, joint_names=JOINTS, joint_torques=[0.0] * 3), raw)
        zeros = [0.0] * THRUSTERS
        self._state_msg = Outgoing(ThrusterState(
            desired_thrust=zeros, actual_thrust=zeros, propeller_speed=zeros,
            reference_speed=zeros, motor_current=zeros), raw)
        self.create_subscription(GeneralizedForce, 'command/generalized_force',
                                 self._on_command, RELIABLE, raw=raw)

    def _on_command(self, msg: Any) -> None:
        t_ns = _stamp_ns(msg)
        self._actuators.publish(self._actuator_msg.stamped(t_ns))
        self._state.publish(self._state_msg.stamped(t_ns))


class FloorVisualizer(Node):
    """Raw contact and controller state in; an empty MarkerArray every 10th state."""

    def __init__(self, context: Context) -> None:
        super().__init__('visualizer', namespace='/uvms', context=context,
                         parameter_overrides=[Parameter('use_sim_time', value=True)])
        self._markers = self.create_publisher(MarkerArray, 'markers', RELIABLE)
        self._states = 0
        self.create_subscription(ContactState, 'contact', lambda data: None, RELIABLE,
                                 raw=True)
        self.create_subscription(ControllerState, 'controller/state', self._on_state,
                                 RELIABLE, raw=True)

    def _on_state(self, data: bytes) -> None:
        self._states += 1
        if self._states % TF_EVERY == 0:
            self._markers.publish(MarkerArray())


class FloorRecorder(Node):
    """Raw subscriptions to every topic; the bytes are dropped."""

    TOPICS = (
        ('/clock', Clock), ('/tf', TFMessage), ('joint_states', JointState),
        ('odometry', Odometry), ('wrench', WrenchStamped), ('ee_pose', PoseStamped),
        ('contact', ContactState), ('command/generalized_force', GeneralizedForce),
        ('controller/state', ControllerState), ('command/actuators', ActuatorCommand),
        ('thrusters/state', ThrusterState), ('markers', MarkerArray),
    )

    def __init__(self, context: Context) -> None:
        super().__init__('recorder', namespace='/uvms', context=context,
                         parameter_overrides=[Parameter('use_sim_time', value=True)])
        self.received = 0
        for topic, msg_type in self.TOPICS:
            qos = QoSProfile(depth=100) if topic == '/tf' else RELIABLE
            self.create_subscription(msg_type, topic, self._on_message, qos, raw=True)

    def _on_message(self, data: bytes) -> None:
        self.received += 1


def run_floor(periods: int, executor_kind: str, recorder: bool,
              raw: bool = False) -> tuple[float, int]:
    """Wall seconds for ``periods`` control periods of the stand-in graph, messages recorded."""
    context = Context()
    rclpy.init(args=[], context=context, signal_handler_options=SignalHandlerOptions.NO)
    try:
        sim = FloorSimulator(context, periods, raw)
        nodes: list[Node] = [sim, FloorController(context, raw), FloorAllocator(context, raw),
                             FloorVisualizer(context)]
        sink = FloorRecorder(context) if recorder else None
        if sink is not None:
            nodes.append(sink)
        executor = make_executor(executor_kind, context)
        for node in nodes:
            executor.add_node(node)
        deadline = time.monotonic() + 5.0
        while time.monotonic() < deadline:  # let discovery match every pair first
            executor.spin_once(timeout_sec=0.05)
        sim.done, sim.t_ns = 0, 0
        start = time.monotonic()
        sim.publish_state()
        while sim.done < periods:
            executor.spin_once(timeout_sec=1.0)
        wall_s = time.monotonic() - start
        received = sink.received if sink is not None else 0
        executor.shutdown()
        for node in nodes:
            node.destroy_node()
    finally:
        rclpy.try_shutdown(context=context)
    return wall_s, received


def main() -> None:
    """Print the floor per control period for the chosen executor(s)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--periods', type=int, default=5000,
                        help='control periods (2 ms of simulated time each); default 5000')
    parser.add_argument('--executor', choices=('events', 'single', 'both'), default='both')
    parser.add_argument('--no-recorder', action='store_true', help='leave the raw sink out')
    parser.add_argument('--pairs', type=int, default=2,
                        help='alternating typed/raw pairs per executor; default 2')
    args = parser.parse_args()
    ros_environment_defaults()
    if not os.environ.get('ROS_DOMAIN_ID'):
        os.environ['ROS_DOMAIN_ID'] = str(random.SystemRandom().randint(*DOMAINS))
    print(f'stand-in graph, {args.periods} control periods ({args.periods * 2e-3:g} s '
          f'simulated), recorder {"off" if args.no_recorder else "raw sink"}; load average '
          + ', '.join(f'{x:.2f}' for x in os.getloadavg()))
    kinds = ('events', 'single') if args.executor == 'both' else (args.executor,)
    for kind in kinds:
        # The first (discovery-settled) run of a kind warms caches; then typed and raw
        # alternate, so that both see the same machine load.
        run_floor(min(args.periods, 500), kind, not args.no_recorder)
        per_period: dict[str, list[float]] = {'typed': [], 'raw': []}
        for _ in range(args.pairs):
            for flavour in ('typed', 'raw'):
                wall_s, received = run_floor(args.periods, kind, not args.no_recorder,
                                             raw=flavour == 'raw')
                per_period[flavour].append(wall_s / args.periods * 1e6)
                print(f'{kind:7s} {flavour:5s} {wall_s:7.2f} s wall, '
                      f'{wall_s / args.periods * 1e6:7.1f} us per control period (real-time '
                      f'factor {args.periods * 2e-3 / wall_s:5.2f}x with no work at all), '
                      f'{received} messages to the recorder')
        typed, raw = min(per_period['typed']), min(per_period['raw'])
        print(f'{kind:7s} floor per control period (best of {args.pairs}): typed {typed:.1f} us, '
              f'raw {raw:.1f} us, raw / typed {raw / typed:.2f}')

if __name__ == '__main__':
    main()
