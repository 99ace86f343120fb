"""The ``alpha5_bridge`` node: ``command/actuators`` to a Reach Alpha 5, its joints to ROS.

A managed node (``autostart``) on the bridges' base (``uvms_hardware.bridge_node``). configure
asks each device in turn (never a broadcast) for MODEL, MODE and its three limits, and
refuses (FAILURE, the log naming the joint and both values) a device whose limits differ from
the URDF's (position, speed) or hardware.yaml's (current), or that stays silent. activate
sends MODE Standby to every device and reads each MODE back (``uvms_hardware.alpha5_probe``:
resent until confirmed, ``CONFIRM_TRIES`` tries of ``confirm_timeout_s``); a device that does
not confirm refuses the activation, naming it. Running, each ``ActuatorCommand`` becomes
CURRENT mA per joint (``uvms_hardware.alpha5_core``); a timer at ``feedback_rate_hz`` x
devices asks one device per tick for POSITION and VELOCITY; the watchdog sends VELOCITY 0 to
every joint after ``watchdog_timeout_s`` without a command and holds. With ``bus_schedule``
(off by default) the commands are held and the timer takes the turns on the half-duplex bus
(``uvms_hardware.alpha5_bus``): every joint's latest CURRENT once per command slot
(hardware.yaml ``alpha5.bus.command_rate_hz``), one device asked per turn while no answer is
on the line.

``joint_states`` carries fresh answers only: one message as soon as every driven joint has
answered position and velocity again (once per round), each answer younger than
``silent_timeout_s``, never the same answers twice. So a joint that stops answering stops
the joint states at once (the controller's input-age check then ends its task INPUTS_STALE)
and /diagnostics turns ERROR naming it. A message of the answering joints only would be
valid ROS (JointState names its joints), but the controller needs every arm joint and would
reject it as a bad input instead of seeing its joint states go stale. Each message is stamped
with the arrival of the oldest answer it holds, on the node clock: the protocol has no device
clock, so arrival (read once per tick, every 2 ms at the defaults) is what the wire gives.

A joint reported over ``overspeed_factor`` x its speed limit trips the bridge: VELOCITY 0 to
every joint (the devices' own speed loop holds them), every command refused; joint_states go
on, so that a controller reset (``uvms hardware reset-trip`` makes one 0.5 s before it clears
the trip) takes its hold where the arm is and is already computing the torque that holds it
(gravity included) when commands are taken again: a command of zero
torque in Current mode lets the light joints fall (measured: a trip again 45 ms after the
reset, with the controller inactive). ``~/reset_trip`` (std_srvs/Trigger, ``uvms hardware
reset-trip``) takes commands again once every joint reports under the trip speed; activate
is refused while a joint is over it (each device asked its speed), naming it, rather than
tripping at once.

deactivate, shutdown, ``on_error``, SIGINT and SIGTERM (the base) stop the arm: VELOCITY 0 to
every device at once, then, device by device and each read back, VELOCITY 0 (MODE Velocity,
or Disable / Passive which ignore it) and the device's mode from before activate (Standby
unless it rested in Disable or Passive); what is not confirmed is an error line naming the
device. With every device silent that takes ``put_back_bound_s`` (0.9 s for five devices at
the defaults). ``/diagnostics``: bad frames, silent joints, HARDWARE_STATUS, watchdog.

Joints: robot.urdf of bluerov2_alpha5 has four arm joints joint_1..joint_4 = devices E, D, C, B
(0x05..0x02). The device's own angle zero is assumed to be the URDF's (unknown from the
documents).

The jaws (0x01) are no URDF joint. When the robot's hardware file names them
(``alpha5.jaw.joint_name``: the ``jaw_joint`` parameter's default; empty: not driven),
the bridge takes ``command/jaw`` (std_msgs/Float64, opening speed m/s, + opens: the
controller's, zero unless a pilot drives) and drives the jaws in Velocity mode (mm/s on the
wire), with the joints' watchdog timeout: no jaw command for ``watchdog_timeout_s`` and they
get VELOCITY 0. Their opening (POSITION, mm on the wire) and speed go to ``jaw_state``
(sensor_msgs/JointState, the one jaw joint, m and m/s), never to ``joint_states``, whose
arm joints the controller takes whole. activate, the put-back (their mode from before) and a
trip treat them as every device.

The device is `uvms_hardware.alpha5_component.Alpha5Component` (no ROS); this node only turns
its lifecycle hooks into the component's, its poll timer into ``read`` and then ``ask`` (in the
robot loop: ``read`` before the control step, ``ask`` after the write), the command topics
into ``write`` and ``write_jaw``, and its state and report into messages.
"""

from __future__ import annotations

import contextlib
from typing import Any

from rcl_interfaces.msg import ParameterDescriptor
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.time import Time
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64
from std_srvs.srv import Trigger
from uvms_common.diagnostics import ERROR, OK, WARN, Report
from uvms_common.node_construction import destroyed_if_construction_fails

from uvms_hardware.alpha5_component import (
    PARAMETERS,
    Alpha5BridgeError,
    Alpha5Component,
    jaw_default,
)
from uvms_hardware.alpha5_core import Alpha5Core
from uvms_hardware.alpha5_feedback import JointSample
from uvms_hardware.bridge_node import DEVICE_TOPIC_QOS, BridgeNode, run_bridge
from uvms_hardware.component import logger_log
from uvms_hardware.device_clock import stop_requested
from uvms_hardware.reach_protocol import Mode
from uvms_hardware.transport import Link
from uvms_msgs.msg import ActuatorCommand

__all__ = ['PARAMETERS', 'Alpha5BridgeError', 'Alpha5BridgeNode', 'main']

_LEVELS = {0: OK, 1: WARN, 2: ERROR}


class Alpha5BridgeNode(BridgeNode):
    """Reach Alpha 5 bridge: actuator commands in, joint_states and diagnostics out."""

    error_type = Alpha5BridgeError
    diagnostics_task = 'alpha5'

    @destroyed_if_construction_fails
    def __init__(self, **kwargs: Any) -> None:
        super().__init__('alpha5_bridge', **kwargs)
        values = {name: self.declare_parameter(
            name, jaw_default(self.robot_name) if default is None else default,
            ParameterDescriptor(description=text, read_only=True)).value
            for name, default, text in PARAMETERS}
        self.component = Alpha5Component(values, self.robot_name, self.get_name(),
                                         clock=self.now_s, log=logger_log(self.get_logger()),
                                         stop_requested=stop_requested)
        self._timer: Any = None
        self.start()

    @property
    def values(self) -> dict[str, Any]:
        """The settings (parameters) of the component."""
        return self.component.values

    @property
    def core(self) -> Alpha5Core | None:
        """The component's protocol core (None while unconfigured)."""
        return self.component.core

    @property
    def link(self) -> Link | None:
        """The component's link (None while unconfigured)."""
        return self.component.link

    @property
    def modes_before(self) -> dict[int, Mode]:
        """Each device's mode before activate, by device id (configure read them)."""
        return self.component.modes_before

    @property
    def configure_errors(self) -> list[str]:
        """Every reason the last configure was refused, one per device problem."""
        return self.component.configure_errors

    # -- the base's hooks ------------------------------------------------------------------
    def configure_device(self) -> None:
        """The component's configure; then the topics, ~/reset_trip and the poll timer."""
        self.component.configure()
        core = self.component.core
        assert core is not None
        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        self._joint_pub = self.own(self.destroy_publisher, self.create_publisher(
            JointState, 'joint_states', DEVICE_TOPIC_QOS))
        self.subscribe(ActuatorCommand, 'command/actuators', self._on_command, qos)
        self.own(self.destroy_service, self.create_service(Trigger, '~/reset_trip',
                                                           self._on_reset_trip))
        if core.arm.jaw is not None:
            self._jaw_pub = self.own(self.destroy_publisher, self.create_publisher(
                JointState, 'jaw_state', DEVICE_TOPIC_QOS))
            self.subscribe(Float64, 'command/jaw', self._on_jaw_command, qos)
        self._timer = self.device_timer(self.component.poll_period_s(), self._on_tick,
                                        then=self._ask)
        self._timer.cancel()  # polls from activate to the put-back only
        drives = core.arm.drives
        self.get_logger().info(
            f'{len(drives)} devices checked on {self.values["connection"]}: ' + ', '.join(
                f'{d.joint_name}={d.device_id:#04x}' for d in drives)
            + (' (from command/jaw, to jaw_state)' if core.arm.jaw else
               '; the jaws (0x01) are not driven'))

    def activate_device(self) -> None:
        """The component's activate (Standby confirmed, no joint over the trip speed); poll."""
        self.component.activate()
        self._timer.reset()

    def put_device_back(self) -> list[str]:
        """The component's put-back; the poll stops."""
        problems = self.component.put_back()
        if self._timer is not None:
            with contextlib.suppress(Exception):  # a timer gone with its context polls no more
                self._timer.cancel()
        return problems

    def release_device(self) -> None:
        """Close the link."""
        self.component.release()
        self._timer = None

    def device_report(self) -> Report:
        """The component's report."""
        report = self.component.report(self.now_s())
        return Report(_LEVELS[report.level], report.message, dict(report.values))

    # -- the period ------------------------------------------------------------------------
    def _on_reset_trip(self, request: Trigger.Request, response: Trigger.Response) -> Any:
        """``~/reset_trip``: take commands again once no joint moves over the trip speed."""
        response.success, response.message = self.component.reset_trip()
        if response.success:
            self.get_logger().info(f'reset_trip: {response.message}')
        else:
            self.get_logger().warning(f'reset_trip refused: {response.message}')
        self.update_diagnostics()
        return response

    def _on_command(self, msg: ActuatorCommand) -> None:
        self.component.write(self.now_s(), (msg.joint_names, msg.joint_torques))

    def _on_jaw_command(self, msg: Float64) -> None:
        self.component.write_jaw(self.now_s(), float(msg.data))

    def _on_tick(self) -> None:
        t_s = self.now_s()
        self.component.read(t_s)
        state = self.component.state()
        if state.joints is not None:
            self._joint_pub.publish(self._joint_state(state.joints, t_s))
        if state.jaw is not None:
            self._jaw_pub.publish(self._joint_state(state.jaw, t_s))

    def _ask(self) -> None:
        """The next requests, after the period's commands (in the robot loop: its write)."""
        self.component.ask(self.now_s())

    def _joint_state(self, sample: JointSample, t_s: float) -> JointState:
        """The message of a sample, stamped with its oldest answer's arrival (node clock)."""
        age_ns = round((t_s - sample.oldest_answer_s) * 1e9)
        now = self.get_clock().now()
        stamp = Time(nanoseconds=max(0, now.nanoseconds - age_ns), clock_type=now.clock_type)
        msg = JointState(name=sample.names, position=sample.positions,
                         velocity=sample.velocities)
        msg.header.stamp = stamp.to_msg()
        return msg


def main(args: list[str] | None = None) -> None:
    """Run the alpha5_bridge node until SIGINT/SIGTERM; the arm is put back first."""
    run_bridge(Alpha5BridgeNode, args, 'alpha5_bridge')


if __name__ == '__main__':
    main()
