"""The alpha5_bridge node against the Alpha 5 twin on 127.0.0.1, on a real rclpy executor."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest
import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.lifecycle import TransitionCallbackReturn
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from uvms_common.lifecycle import state_label
from uvms_hardware.alpha5_bridge_node import Alpha5BridgeError, Alpha5BridgeNode
from uvms_hardware.hardware_config import load_alpha5
from uvms_hardware.reach_protocol import Mode, PacketId
from uvms_twins.alpha5_twin import Alpha5Twin

from uvms_msgs.msg import ActuatorCommand

ROBOT = 'bluerov2_alpha5'
JOINTS = ['joint_1', 'joint_2', 'joint_3', 'joint_4']
SUCCESS, FAILURE = TransitionCallbackReturn.SUCCESS, TransitionCallbackReturn.FAILURE


class Rig:
    """A twin with the jaw, a probe node and the bridge on one executor."""

    def __init__(self) -> None:
        self.twin = Alpha5Twin(load_alpha5(ROBOT, jaw_joint='jaw'), port=0)
        self.twin.start()
        self.context = Context()
        rclpy.init(args=[], context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.probe = rclpy.create_node('probe', namespace='uvms', context=self.context)
        self.executor.add_node(self.probe)
        self.command = self.probe.create_publisher(ActuatorCommand, 'command/actuators', 10)
        self.states: list[JointState] = []
        self.probe.create_subscription(JointState, 'joint_states', self.states.append, 1000)
        self.diagnostics: list[DiagnosticArray] = []
        self.probe.create_subscription(DiagnosticArray, '/diagnostics',
                                       self.diagnostics.append, 100)
        self.bridge: Alpha5BridgeNode | None = None

    def start_bridge(self, **parameters: Any) -> Alpha5BridgeNode:
        """The bridge on the twin's port with ``parameters`` (autostart unless given)."""
        values = {'robot_name': ROBOT, 'connection': f'udp:127.0.0.1:{self.twin.port}',
                  **parameters}
        overrides = [Parameter(k, value=v) for k, v in values.items()]
        self.bridge = Alpha5BridgeNode(namespace='uvms', context=self.context,
                                       parameter_overrides=overrides)
        self.executor.add_node(self.bridge)
        return self.bridge

    def spin_until(self, done: Callable[[], bool], timeout_s: float = 10.0) -> None:
        """Spin until done() or fail after the timeout."""
        deadline = time.monotonic() + timeout_s
        while not done():
            assert time.monotonic() < deadline, 'timed out spinning'
            self.executor.spin_once(timeout_sec=0.01)

    def spin_for(self, duration_s: float, command: list[float] | None = None) -> None:
        """Spin ``duration_s``, publishing ``command`` torques at 50 Hz when given."""
        end = time.monotonic() + duration_s
        next_s = 0.0
        while time.monotonic() < end:
            if command is not None and time.monotonic() >= next_s:
                self.command.publish(ActuatorCommand(joint_names=JOINTS, joint_torques=command))
                next_s = time.monotonic() + 0.02
            self.executor.spin_once(timeout_sec=0.005)

    def close(self) -> None:
        """Bridge, probe, context and twin gone."""
        self.executor.shutdown()
        if self.bridge is not None:
            self.bridge.destroy_node()
        self.probe.destroy_node()
        rclpy.try_shutdown(context=self.context)
        self.twin.stop()


def wait_for(done: Callable[[], bool], timeout_s: float = 2.0) -> None:
    """Poll the twin (its own thread) until done(), or fail."""
    deadline = time.monotonic() + timeout_s
    while not done():
        assert time.monotonic() < deadline, 'the twin did not get there in time'
        time.sleep(0.005)


@pytest.fixture
def rig() -> Iterator[Rig]:
    """A fresh twin and executor, closed after the test."""
    made = Rig()
    yield made
    made.close()


def test_torque_commands_reach_the_twin_as_currents(rig: Rig) -> None:
    """2 N m on joint_1 puts device E in Current mode at 2/(Kt ratio eff) mA."""
    rig.start_bridge()
    rig.spin_for(0.3, command=[2.0, 0.0, 0.0, 0.0])
    mode, current_ma = rig.twin.joint_commands()['joint_1']
    assert mode == Mode.CURRENT
    assert current_ma == pytest.approx(2000.0 / (0.0134 * 1754.4 * 0.86), rel=1e-5)


def test_watchdog_sends_velocity_0_to_every_joint_within_0_2_s(rig: Rig) -> None:
    """Commands stop: within 0.2 s of the last CURRENT, VELOCITY 0 reaches all four devices."""
    rig.start_bridge()
    rig.spin_for(0.3, command=[1.0, 1.0, 1.0, 1.0])
    rig.spin_for(0.4)
    for device_id in (5, 4, 3, 2):
        received = rig.twin.received(device_id)
        last_current_s = max(t for t, p in received if p.packet_id == PacketId.CURRENT)
        zero_s = min(t for t, p in received if p.packet_id == PacketId.VELOCITY
                     and t > last_current_s and p.floats() == (0.0,))
        assert zero_s - last_current_s <= 0.2
    assert {m for j, (m, _) in rig.twin.joint_commands().items() if j != 'jaw'} == {
        Mode.VELOCITY}
    assert rig.bridge is not None and rig.bridge.core is not None and rig.bridge.core.holding


def test_jaw_state_carries_the_jaw_in_metres_apart_from_joint_states(rig: Rig) -> None:
    """The twin's jaw at 0.012 m (12 mm on the wire) is 0.012 on jaw_state; joint_states: 4."""
    jaws: list[JointState] = []
    rig.probe.create_subscription(JointState, 'jaw_state', jaws.append, 100)
    rig.twin.set_joint_state([0.5, -1.0, 1.5, 2.0, 0.012], [0.01, 0.0, 0.0, 0.0, 0.001])
    rig.start_bridge(jaw_joint='jaw')
    rig.spin_until(lambda: len(rig.states) >= 5 and len(jaws) >= 2)
    assert list(rig.states[-1].name) == JOINTS
    assert list(rig.states[-1].position) == pytest.approx([0.5, -1.0, 1.5, 2.0], abs=1e-6)
    assert list(jaws[-1].name) == ['jaw']
    assert jaws[-1].position[0] == pytest.approx(0.012, abs=1e-6)
    assert jaws[-1].velocity[0] == pytest.approx(0.001)


def test_joint_states_without_jaw_name_only_the_urdf_joints(rig: Rig) -> None:
    """jaw_joint empty: the jaw is not driven: four joints, no packet goes to device 0x01."""
    rig.start_bridge(jaw_joint='')
    rig.spin_until(lambda: len(rig.states) >= 3)
    assert list(rig.states[-1].name) == JOINTS
    assert rig.twin.received(0x01) == []


def test_joint_states_rate_per_joint(rig: Rig) -> None:
    """At the default rate every joint is refreshed at least 100 times a second."""
    rig.start_bridge()
    rig.spin_until(lambda: len(rig.states) >= 1)
    before = len(rig.states)
    rig.spin_for(1.0)
    assert len(rig.states) - before >= 100, len(rig.states) - before


def test_limit_mismatch_is_refused_naming_the_joint(rig: Rig) -> None:
    """A shoulder configured 0..3.8 rad: configure fails naming joint_2, 3.8 and 3.49."""
    rig.twin.set_position_limits(0x04, 0.0, 3.8)
    bridge = rig.start_bridge(autostart=False)
    assert bridge.trigger_configure() == FAILURE
    (error,) = bridge.configure_errors
    assert 'joint_2' in error and '3.8' in error and '3.49' in error
    assert state_label(bridge) == 'unconfigured'


def test_silent_joint_is_refused(rig: Rig) -> None:
    """The wrist answering nothing: configure fails naming joint_4 as silent."""
    rig.twin.set_silent(0x02)
    bridge = rig.start_bridge(autostart=False, answer_timeout_s=0.1, startup_wait_s=0.5)
    assert bridge.trigger_configure() == FAILURE
    assert bridge.configure_errors == ['joint_4 (device 0x02, B): silent: no MODEL answer '
                                       'within 0.1 s']


def test_autostart_refusal_raises_with_the_reason(rig: Rig) -> None:
    """Autostart on a mismatching arm raises Alpha5BridgeError naming the joint."""
    rig.twin.set_position_limits(0x03, 0.0, 3.0)
    with pytest.raises(Alpha5BridgeError, match='joint_3'):
        rig.start_bridge()
    rig.bridge = None


def test_deactivate_restores_standby(rig: Rig) -> None:
    """After commands, deactivate sends VELOCITY 0 then MODE Standby to every device.

    Each is read back (a REQUEST follows each change, left out here).
    """
    bridge = rig.start_bridge()
    rig.spin_for(0.2, command=[0.5, 0.5, 0.5, 0.5])
    assert bridge.trigger_deactivate() == SUCCESS
    wait_for(lambda: {rig.twin.joint_commands()[j][0] for j in JOINTS} == {Mode.STANDBY})
    changes = [[p.packet_id for _, p in rig.twin.received(d) if p.packet_id != PacketId.REQUEST]
               for d in (5, 4, 3, 2)]
    assert all(sent[-2:] == [PacketId.VELOCITY, PacketId.MODE] for sent in changes)


def test_destroy_leaves_the_arm_in_standby(rig: Rig) -> None:
    """Destroying the active node (SIGINT/SIGTERM path) leaves every device in Standby."""
    bridge = rig.start_bridge()
    rig.spin_for(0.2, command=[0.5, 0.5, 0.5, 0.5])
    rig.executor.remove_node(bridge)
    bridge.destroy_node()
    rig.bridge = None
    wait_for(lambda: {rig.twin.joint_commands()[j][0] for j in JOINTS} == {Mode.STANDBY})


def test_bad_frame_is_counted_and_survived(rig: Rig) -> None:
    """Garbage from the device's port is counted on /diagnostics; joint_states go on."""
    bridge = rig.start_bridge()
    rig.spin_until(lambda: len(rig.states) >= 2)
    assert bridge.core is not None and bridge.link is not None
    sock = rig.twin._socket
    assert sock is not None
    bridge_port = bridge.link._socket.getsockname()[1]  # type: ignore[attr-defined]
    sock.sendto(b'\x05\x01\x02\x03\x04\x00\x03\x01\x02\x00', ('127.0.0.1', bridge_port))
    before = len(rig.states)
    rig.spin_until(lambda: bridge.core is not None and bridge.core.splitter.bad_frames >= 2)
    rig.spin_until(lambda: len(rig.states) >= before + 5)
    rig.diagnostics.clear()
    rig.spin_until(lambda: any(s.name == 'alpha5_bridge: alpha5' for a in rig.diagnostics
                               for s in a.status), timeout_s=5.0)
    status = next(s for a in rig.diagnostics for s in a.status
                  if s.name == 'alpha5_bridge: alpha5')
    values = {kv.key: kv.value for kv in status.values}
    assert int(values['crc_errors']) + int(values['length_errors']) + int(
        values['cobs_errors']) >= 2
    assert state_label(bridge) == 'active'
