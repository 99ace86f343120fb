"""The ``alpha5_bridge`` node: ``command/actuators`` to a Reach Alpha 5, its joints to ROS.

A managed node (``autostart``). configure asks each device in turn (never a broadcast) for
MODEL, MODE and its three limits, and refuses (FAILURE, the log naming the joint and both
values) a device whose limits differ from the URDF's (position, speed) or hardware.yaml's
(current), or that stays silent. activate sends MODE Standby to every device. Running, each
``ActuatorCommand`` becomes CURRENT mA per joint (``uvms_hardware.alpha5_core``); a timer at
``feedback_rate_hz`` x devices asks one device per tick for POSITION and VELOCITY and
publishes ``joint_states`` once per round; the watchdog sends VELOCITY 0 to every joint after
``watchdog_timeout_s`` without a command and holds. deactivate, shutdown, SIGINT and SIGTERM
send VELOCITY 0, then each device's mode from before activate (Standby unless it rested in
Disable or Passive). ``/diagnostics``: bad frames, silent joints, HARDWARE_STATUS, watchdog.

Joints: robot.urdf of bluerov2_alpha5 has four arm joints joint_1..joint_4 = devices E, D, C, B
(0x05..0x02); the jaw (0x01) is no URDF joint and is not driven unless ``jaw_joint`` names
it (then reported in m, as every ROS-facing length). The device's own angle zero is assumed
to be the URDF's (unknown from the documents).
"""

from __future__ import annotations

import math
import sys
from typing import Any

from rcl_interfaces.msg import ParameterDescriptor
from rclpy.exceptions import ParameterException
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rclpy.qos import QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from uvms_common.diagnostics import ERROR, OK, WARN, DiagnosticsPublisher, Report
from uvms_common.lifecycle import autostart, declare_autostart, guard_change_state, state_label
from uvms_common.node_main import run_node
from uvms_common.robot_parameters import declare_robot_name

from uvms_hardware.alpha5_core import (
    DEFAULT_OVERSPEED_FACTOR,
    Alpha5Core,
    check_device,
)
from uvms_hardware.alpha5_probe import probe_device
from uvms_hardware.device_clock import DeviceClock, stop_requested
from uvms_hardware.errors import HardwareError
from uvms_hardware.hardware_config import Drive, load_alpha5
from uvms_hardware.reach_protocol import Mode
from uvms_hardware.transport import Link, open_link, parse_connection
from uvms_msgs.msg import ActuatorCommand

SUCCESS, FAILURE = TransitionCallbackReturn.SUCCESS, TransitionCallbackReturn.FAILURE
_LEVELS = {0: OK, 1: WARN, 2: ERROR}

#: name, default, description (unit).
PARAMETERS: tuple[tuple[str, Any, str], ...] = (
    ('connection', 'udp:127.0.0.1:6789',
     'udp:HOST:PORT, or serial:DEVICE[:BAUD] (8N1, 115200 unless given)'),
    ('watchdog_timeout_s', 0.1, 'No command for this long: VELOCITY 0 to every joint (s)'),
    ('feedback_rate_hz', 125.0,
     'Each device is asked this often, joint_states published once per round (Hz); above '
     '100 so that a late timer on a busy host still gives >= 100 Hz per joint'),
    ('command_mode', 'current',
     'current: torque as CURRENT mA (Kt, gear, efficiency); velocity: a fallback, '
     'VELOCITY = velocity_gain_rad_s_per_n_m * torque'),
    ('velocity_gain_rad_s_per_n_m', 0.1, 'Admittance of the velocity fallback (rad/s per N m)'),
    ('jaw_joint', '', "The jaws' joint name; empty: the jaws are not driven (no URDF joint)"),
    ('answer_timeout_s', 0.2, 'Time a device has to answer at configure (s)'),
    ('startup_wait_s', 10.0,
     'While no device answers at all, configure asks again for this long (s): the arm or its '
     'link may come up after the bridge (launch order); 0 asks once'),
    ('silent_timeout_s', 0.2, 'A joint without an answer this long is silent (s)'),
    ('overspeed_factor', DEFAULT_OVERSPEED_FACTOR,
     'A joint reported faster than this many times its URDF speed limit trips the bridge: '
     'VELOCITY 0 to every joint, commands refused until deactivate and activate (>= 1)'),
)


class Alpha5BridgeError(HardwareError):
    """A parameter of the bridge is invalid."""


class Alpha5BridgeNode(LifecycleNode):
    """Reach Alpha 5 bridge: actuator commands in, joint_states and diagnostics out."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__('alpha5_bridge', **kwargs)
        self._device_clock = DeviceClock(self)
        self.robot_name = declare_robot_name(self)
        self.values = {name: self.declare_parameter(
            name, default, ParameterDescriptor(description=text, read_only=True)).value
            for name, default, text in PARAMETERS}
        starting = declare_autostart(self)
        guard_change_state(self)
        self.core: Alpha5Core | None = None
        self.link: Link | None = None
        self.modes_before: dict[int, Mode] = {}
        self.configure_errors: list[str] = []
        self._entities: list[Any] = []
        self._timer: Any = None
        self._active = False
        self._diagnostics = DiagnosticsPublisher(self, self.robot_name)
        self._diagnostics.add('alpha5', self._report)
        if starting and not autostart(self):
            message = '; '.join(self.configure_errors) or 'the bridge cannot configure'
            self.destroy_node()
            raise Alpha5BridgeError(message)

    def now_s(self) -> float:
        """The steady clock (s): the device's times (``uvms_hardware.device_clock``)."""
        return self._device_clock.now_s()

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Open the link, check every device in turn, create publisher and subscription."""
        v = self.values
        try:
            arm = load_alpha5(self.robot_name, str(v['jaw_joint']))
            core = Alpha5Core(arm, float(v['watchdog_timeout_s']), str(v['command_mode']),
                              float(v['velocity_gain_rad_s_per_n_m']),
                              float(v['silent_timeout_s']), float(v['overspeed_factor']))
            if not float(v['feedback_rate_hz']) > 0.0:
                raise Alpha5BridgeError(f'feedback_rate_hz = {v["feedback_rate_hz"]}: > 0')
            link = open_link(parse_connection(str(v['connection']), arm.udp_port))
        except (HardwareError, ValueError) as exc:
            return self._refuse([str(exc)])
        deadline_s = self.now_s() + float(v['startup_wait_s'])
        while True:
            self.modes_before.clear()
            errors = [e for drive in arm.drives for e in self._check(link, core, drive)]
            answered = all(d.device_id in self.modes_before for d in arm.drives)
            if answered or self.now_s() >= deadline_s or stop_requested():
                break
            self.get_logger().info(f'not every device answers on {v["connection"]} yet: '
                                   'asking again', throttle_duration_sec=2.0)
        if errors:
            link.close()
            return self._refuse(errors)
        self.core, self.link = core, link
        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        self._joint_pub = self.create_publisher(JointState, 'joint_states', qos)
        self._entities = [(self.destroy_publisher, self._joint_pub), (
            self.destroy_subscription, self.create_subscription(
                ActuatorCommand, 'command/actuators', self._on_command, qos))]
        self.get_logger().info(
            f'{len(arm.drives)} devices checked on {v["connection"]}: ' + ', '.join(
                f'{d.joint_name}={d.device_id:#04x}' for d in arm.drives)
            + ('' if arm.jaw else '; the jaws (0x01) are not driven'))
        return SUCCESS

    def _check(self, link: Link, core: Alpha5Core, drive: Drive) -> list[str]:
        timeout_s = float(self.values['answer_timeout_s'])
        answers, mode = probe_device(link, core.splitter, drive, timeout_s)
        if mode is not None:
            self.modes_before[drive.device_id] = mode
        return check_device(drive, answers, timeout_s)

    def _refuse(self, errors: list[str]) -> TransitionCallbackReturn:
        self.configure_errors = errors
        for error in errors:
            self.get_logger().error(f'configure refused: {error}')
        return FAILURE

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """MODE Standby to every device, then poll and accept commands."""
        assert self.core is not None and self.link is not None
        self.link.send(self.core.standby_frames())
        period_s = 1.0 / (float(self.values['feedback_rate_hz']) * len(self.core.drives))
        self._timer = self._device_clock.timer(period_s, self._on_tick)
        self._active = True
        return super().on_activate(state)

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """VELOCITY 0, then each device's mode from before activate."""
        self._stop()
        return super().on_deactivate(state)

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Close the link, drop publisher and subscription."""
        self._release()
        return super().on_cleanup(state)

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Leave the arm at rest from any state, then release everything."""
        self._stop()
        self._release()
        return super().on_shutdown(state)

    def destroy_node(self) -> None:
        """Shut down as rclcpp's lifecycle node does (arm at rest), then destroy."""
        if state_label(self) not in ('finalized', 'unknown') and self.context.ok():
            self.trigger_shutdown()
        else:
            self._stop()
        self._diagnostics.destroy()
        super().destroy_node()

    def _stop(self) -> None:
        if self._timer is not None:
            self.destroy_timer(self._timer)
            self._timer = None
        if self._active and self.core is not None and self.link is not None:
            self.link.send(self.core.restore_frames(self.modes_before))
            self.core.stop_driving()
        self._active = False

    def _release(self) -> None:
        for destroy, entity in reversed(self._entities):
            destroy(entity)
        self._entities = []
        if self.link is not None:
            self.link.close()
        self.link, self.core = None, None

    def _on_command(self, msg: ActuatorCommand) -> None:
        if not self._active or self.core is None or self.link is None:
            return
        frames = self.core.command(self.now_s(), list(msg.joint_names), list(msg.joint_torques))
        if not frames:
            self.get_logger().error(f'command refused: {self.core.last_rejection}',
                                    throttle_duration_sec=1.0)
        self.link.send(frames)

    def _on_tick(self) -> None:
        core, link = self.core, self.link
        if core is None or link is None:
            return
        t_s = self.now_s()
        tripped = core.overspeed
        core.receive(link.read(), t_s)
        if core.overspeed and not tripped:
            self.get_logger().error(f'tripped: {core.overspeed}: VELOCITY 0 to every joint; '
                                    'commands refused until deactivate and activate')
        frames, round_done = core.tick(t_s)
        link.send(frames)
        if round_done and self._active:
            names, positions, velocities = core.joint_state()
            if not all(math.isfinite(x) for x in positions + velocities):
                return  # a device has not answered yet: nothing is published before
            msg = JointState(name=names, position=positions, velocity=velocities)
            msg.header.stamp = self.get_clock().now().to_msg()
            self._joint_pub.publish(msg)

    def _report(self) -> Report:
        state = state_label(self)
        if self.core is None:
            text = '; '.join(self.configure_errors) or 'not configured'
            return Report(ERROR if self.configure_errors else WARN, f'{state}: {text}',
                          {'lifecycle_state': state})
        level, message, values = self.core.report(self.now_s())
        return Report(_LEVELS[level], message, {'lifecycle_state': state, **values})


def main(args: list[str] | None = None) -> None:
    """Run the alpha5_bridge node until SIGINT/SIGTERM."""
    sys.exit(run_node(Alpha5BridgeNode, args, 'alpha5_bridge',
                      (Alpha5BridgeError, HardwareError, ParameterException)))


if __name__ == '__main__':
    main()
