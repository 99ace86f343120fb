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
every joint after ``watchdog_timeout_s`` without a command and holds.

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

from uvms_hardware.alpha5_core import (
    CONFIRM_TRIES,
    DEFAULT_CONFIRM_TIMEOUT_S,
    DEFAULT_OVERSPEED_FACTOR,
    FEEDBACK_REQUEST,
    PUT_BACK_BUDGET_S,
    Alpha5Core,
    JointSample,
    Setting,
    check_device,
    describe,
    put_back_bound_s,
)
from uvms_hardware.alpha5_probe import confirm_setting, probe_device
from uvms_hardware.bridge_node import REFUSALS, BridgeNode, run_bridge
from uvms_hardware.device_clock import stop_requested
from uvms_hardware.errors import HardwareError
from uvms_hardware.hardware_config import Drive, load_alpha5
from uvms_hardware.reach_protocol import Mode, encode_request
from uvms_hardware.stop_report import write_stop_report
from uvms_hardware.transport import Link, open_link, parse_connection
from uvms_msgs.msg import ActuatorCommand

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
    ('jaw_joint', None,
     "The jaws' joint name, driven from command/jaw; empty: the jaws are not driven. "
     "Default: hardware.yaml's alpha5.jaw.joint_name (empty where it names none)"),
    ('answer_timeout_s', 0.2, 'Time a device has to answer at configure (s)'),
    ('startup_wait_s', 10.0,
     'While no device answers at all, configure asks again for this long (s): the arm or its '
     'link may come up after the bridge (launch order); 0 asks once'),
    ('silent_timeout_s', 0.2,
     'A joint without an answer this long is silent: no joint_states, diagnostics ERROR (s)'),
    ('overspeed_factor', DEFAULT_OVERSPEED_FACTOR,
     'A joint reported faster than this many times its URDF speed limit trips the bridge: '
     'VELOCITY 0 to every joint, commands refused until ~/reset_trip or deactivate and '
     'activate (>= 1)'),
    ('confirm_timeout_s', DEFAULT_CONFIRM_TIMEOUT_S,
     f'Wait for a MODE read-back when activate or the put-back confirms a change (s); '
     f'{CONFIRM_TRIES} tries per change, and the whole put-back with every device silent '
     f'must fit {PUT_BACK_BUDGET_S:g} s'),
)


def _jaw_default(robot_name: str) -> str:
    """The jaws' joint name the robot's hardware file gives ('' where none or unreadable)."""
    try:
        jaw = load_alpha5(robot_name, None).jaw
    except HardwareError:
        return ''  # configure names what is wrong with the file
    return '' if jaw is None else jaw.joint_name


class Alpha5BridgeError(HardwareError):
    """A parameter of the bridge is invalid, or the arm refuses configure or activate."""


class Alpha5BridgeNode(BridgeNode):
    """Reach Alpha 5 bridge: actuator commands in, joint_states and diagnostics out."""

    error_type = Alpha5BridgeError
    diagnostics_task = 'alpha5'

    def __init__(self, **kwargs: Any) -> None:
        super().__init__('alpha5_bridge', **kwargs)
        self.values = {name: self.declare_parameter(
            name, _jaw_default(self.robot_name) if default is None else default,
            ParameterDescriptor(description=text, read_only=True)).value
            for name, default, text in PARAMETERS}
        self.core: Alpha5Core | None = None
        self.link: Link | None = None
        self.modes_before: dict[int, Mode] = {}
        #: Every reason the last configure was refused, one per device problem.
        self.configure_errors: list[str] = []
        self._timer: Any = None
        self.start()

    # -- the base's hooks ------------------------------------------------------------------
    def configure_device(self) -> None:
        """Check parameters, open the link, check every device in turn, create the entities."""
        self.configure_errors = []
        try:
            self._configure()
        except REFUSALS as exc:
            self.configure_errors = self.configure_errors or [str(exc)]
            raise

    def _configure(self) -> None:
        v = self.values
        arm = load_alpha5(self.robot_name, str(v['jaw_joint']))
        core = Alpha5Core(arm, float(v['watchdog_timeout_s']), str(v['command_mode']),
                          float(v['velocity_gain_rad_s_per_n_m']),
                          float(v['silent_timeout_s']), float(v['overspeed_factor']))
        rate_hz = float(v['feedback_rate_hz'])
        if not rate_hz > 0.0:
            raise Alpha5BridgeError(f'feedback_rate_hz = {rate_hz}: expected > 0')
        bound_s = put_back_bound_s(len(arm.drives), CONFIRM_TRIES, float(v['confirm_timeout_s']))
        if not 0.0 < bound_s <= PUT_BACK_BUDGET_S:
            raise Alpha5BridgeError(
                f'confirm_timeout_s = {v["confirm_timeout_s"]}: the put-back of '
                f'{len(arm.drives)} devices could take {bound_s:g} s, more than '
                f'{PUT_BACK_BUDGET_S:g} s (or is no time at all)')
        self.link = link = open_link(parse_connection(str(v['connection']), arm.udp_port))
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
            self.configure_errors = errors
            raise Alpha5BridgeError('; '.join(errors))
        self.core = core
        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        self._joint_pub = self.own(self.destroy_publisher,
                                   self.create_publisher(JointState, 'joint_states', qos))
        self.own(self.destroy_subscription, self.create_subscription(
            ActuatorCommand, 'command/actuators', self._on_command, qos))
        self.own(self.destroy_service, self.create_service(Trigger, '~/reset_trip',
                                                           self._on_reset_trip))
        if arm.jaw is not None:
            self._jaw_pub = self.own(self.destroy_publisher,
                                     self.create_publisher(JointState, 'jaw_state', qos))
            self.own(self.destroy_subscription, self.create_subscription(
                Float64, 'command/jaw', self._on_jaw_command, qos))
        self._timer = self.device_timer(core.poll_period_s(rate_hz), self._on_tick)
        self._timer.cancel()  # polls from activate to the put-back only
        self.get_logger().info(
            f'{len(arm.drives)} devices checked on {v["connection"]}: ' + ', '.join(
                f'{d.joint_name}={d.device_id:#04x}' for d in arm.drives)
            + (' (from command/jaw, to jaw_state)' if arm.jaw else
               '; the jaws (0x01) are not driven'))

    def _check(self, link: Link, core: Alpha5Core, drive: Drive) -> list[str]:
        timeout_s = float(self.values['answer_timeout_s'])
        answers, mode = probe_device(link, core.splitter, drive, timeout_s)
        if mode is not None:
            self.modes_before[drive.device_id] = mode
        return check_device(drive, answers, timeout_s)

    def activate_device(self) -> None:
        """MODE Standby to every device, each read back; then poll and accept commands.

        Raises:
            Alpha5BridgeError: A device did not confirm Standby (named); the base then puts
                back every device.
        """
        assert self.core is not None and self.link is not None
        self.link.read()  # answers still in flight from configure
        problems = self._confirm(self.core.standby_settings())
        if problems:
            raise Alpha5BridgeError('; '.join(problems))
        self.core.stop_driving()  # nothing is driven until the first command
        fast = self._fast_joints_now()
        if fast:
            raise Alpha5BridgeError(
                f'{", ".join(fast)}: over {self.core.overspeed_factor:g} x the speed limit, '
                'the bridge would trip at once; wait until the arm is still (after a trip: '
                'docs/hardware.md, "Recovering the arm after a trip")')
        self._timer.reset()

    def _fast_joints_now(self) -> list[str]:
        """Each device asked its speed now: the joints over the trip speed (activate)."""
        assert self.core is not None and self.link is not None
        timeout_s = float(self.values['confirm_timeout_s'])
        for drive in self.core.drives:
            self.link.send(encode_request(drive.device_id, FEEDBACK_REQUEST))
            deadline_s = self.now_s() + timeout_s
            before = self.core.feedback[drive.device_id].velocity_s
            while (self.core.feedback[drive.device_id].velocity_s == before
                   and self.now_s() < deadline_s):
                self.link.wait(deadline_s - self.now_s())
                self.core.receive(self.link.read(), self.now_s())
        fast = self.core.fast_joints()
        self.core.stop_driving()  # a trip receive() just found is said by the refusal
        return fast

    def _on_reset_trip(self, request: Trigger.Request, response: Trigger.Response) -> Any:
        """``~/reset_trip``: take commands again once no joint moves over the trip speed."""
        core = self.core
        if core is None or not self.device_active:
            response.success, response.message = False, 'not active: activate instead'
            return response
        tripped = core.overspeed
        if not tripped:
            response.success, response.message = True, 'not tripped: nothing to clear'
            return response
        why = core.reset_trip()
        response.success = not why
        response.message = why or f'trip cleared ({tripped}); commands are taken again'
        if response.success:
            self.get_logger().info(f'reset_trip: {response.message}')
        else:
            self.get_logger().warning(f'reset_trip refused: {response.message}')
        self.update_diagnostics()
        return response

    def put_device_back(self) -> list[str]:
        """VELOCITY 0 to every device at once, then each VELOCITY 0 and resting mode confirmed.

        Returns:
            One line per change a device did not confirm, naming it.
        """
        core, link = self.core, self.link
        problems: list[str] = []
        if core is not None and link is not None:
            link.send(core.neutral_frames())  # every joint stops first, whatever follows
            settings = core.restore_settings(self.modes_before)
            problems = self._confirm(settings)
            core.stop_driving()
            rest = ', '.join(f'{s.drive.joint_name} {s.label.removeprefix("MODE ")}'
                             for s in settings if s.label.startswith('MODE'))
            done = (f'every joint VELOCITY 0, then its mode from before ({rest}), '
                    + ('each read back' if not problems else
                       f'{len(problems)} of {len(settings)} changes NOT confirmed'))
            self.get_logger().info(f'put back: {done}')
            write_stop_report(self.get_name(), done, problems)
        if self._timer is not None:
            with contextlib.suppress(Exception):  # a timer gone with its context polls no more
                self._timer.cancel()
        return problems

    def release_device(self) -> None:
        """Close the link."""
        if self.link is not None:
            self.link.close()
        self.link, self.core, self._timer = None, None, None

    def device_report(self) -> Report:
        """Bad frames, silent joints, HARDWARE_STATUS, watchdog; OK while not driving."""
        if self.core is None:
            return Report(WARN, 'not configured', {})
        if not self.device_active:
            return Report(OK, 'not driving', {})
        level, message, values = self.core.report(self.now_s())
        return Report(_LEVELS[level], message, values)

    # -- the period ------------------------------------------------------------------------
    def _confirm(self, settings: list[Setting]) -> list[str]:
        """Each setting sent and read back (``confirm_setting``); what did not confirm."""
        assert self.core is not None and self.link is not None
        timeout_s = float(self.values['confirm_timeout_s'])
        problems = []
        for setting in settings:
            result = confirm_setting(self.link, self.core.splitter, setting, CONFIRM_TRIES,
                                     timeout_s)
            if not result.confirmed:
                seen = ('no MODE answer' if result.mode is None
                        else f'MODE reads {result.mode.name.capitalize()}')
                problems.append(f'{describe(setting.drive)}: {setting.label} not confirmed '
                                f'after {result.tries} tries of {timeout_s:g} s ({seen})')
        return problems

    def _on_command(self, msg: ActuatorCommand) -> None:
        if not self.device_active or self.core is None or self.link is None:
            return
        frames = self.core.command(self.now_s(), list(msg.joint_names), list(msg.joint_torques))
        if not frames:
            self.get_logger().error(f'command refused: {self.core.last_rejection}',
                                    throttle_duration_sec=1.0)
        self.link.send(frames)

    def _on_jaw_command(self, msg: Float64) -> None:
        if not self.device_active or self.core is None or self.link is None:
            return
        frames, refused = self.core.jaw_command(self.now_s(), float(msg.data))
        if refused:
            self.get_logger().error(f'jaw command refused: {refused}', throttle_duration_sec=1.0)
        self.link.send(frames)

    def _on_tick(self) -> None:
        core, link = self.core, self.link
        if core is None or link is None or not self.device_active:
            return
        t_s = self.now_s()
        tripped = core.overspeed
        core.receive(link.read(), t_s)
        if core.overspeed and not tripped:
            self.get_logger().error(f'tripped: {core.overspeed}: VELOCITY 0 to every joint; '
                                    'commands refused until `uvms hardware reset-trip` '
                                    '(docs/hardware.md, "Recovering the arm after a trip")')
        sample = core.next_joint_state(t_s)  # as soon as every joint answered again
        if sample is not None:
            self._joint_pub.publish(self._joint_state(sample, t_s))
        jaw = core.next_jaw_state(t_s)
        if jaw is not None:
            self._jaw_pub.publish(self._joint_state(jaw, t_s))
        frames, _ = core.tick(t_s)
        link.send(frames)

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
