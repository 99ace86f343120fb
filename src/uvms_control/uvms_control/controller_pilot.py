"""The controller node's pilot interface: pilot topics, the mode, the hold service, the script.

A mixin of ``ControllerNode`` (as ``controller_safety`` is). Subscribes ``pilot/vehicle_twist``
and ``pilot/ee_twist`` (geometry_msgs/TwistStamped) and ``pilot/jaw`` (std_msgs/Float64);
publishes ``controller/mode`` (std_msgs/String, latched: 'pilot', 'task' or 'hold') at every
switch; serves ``controller/hold`` (std_srvs/Trigger). The jaw has one owner, the controller:
it publishes ``command/jaw`` (std_msgs/Float64, m/s, + opens) at every control step while
the jaw speed is not zero, the pilot's in pilot mode (deadman-limited, within
``pilot.max_jaw_speed_m_s``), then one zero when it stops (hold, task, deadman) and nothing
while it stays zero, so that no message is built per step for a jaw at rest; the Alpha 5
bridge drives the jaws from it (its watchdog stops them when the commands stop, as it stops
the joints when ``command/actuators`` stops). Messages are
checked and bounded by ``core.pilot.inputs`` against the robot's ``pilot.*`` limits, each kind
of refusal named once per topic; the hand-over (``core.pilot.handover``) runs in the control
step, before the task supervisor's. ``pilot.script`` (a scenario's ``pilot:``) plays timed
commands through the same checks, stamped with the step's time, so a pilot session runs the
same in every lockstep run. Each switch is one console line and an immediate /diagnostics
report ('pilot').
"""

from __future__ import annotations

from typing import Any

from geometry_msgs.msg import TwistStamped
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import Float64, String
from std_srvs.srv import Trigger
from uvms_common.diagnostics import OK, WARN, Report

from uvms_control.core.pilot.handover import PilotHandover, PilotMode
from uvms_control.core.pilot.inputs import (
    PilotInputError,
    Refusal,
    RefusalLog,
    check_stamp,
    ee_twist,
    jaw_speed,
    vehicle_twist,
)
from uvms_control.core.pilot.limits import PILOT_PARAMETER_SPECS, PilotLimits
from uvms_control.core.pilot.script import ScriptCommand, ScriptPlayer, load_script_text
from uvms_control.node_safety import guarded
from uvms_control.ros_parameters import declare_parameters

#: The pilot's topics (relative: /uvms/pilot/... in the /uvms namespace).
VEHICLE_TOPIC = 'pilot/vehicle_twist'
EE_TOPIC = 'pilot/ee_twist'
JAW_TOPIC = 'pilot/jaw'
#: The jaw speed the controller forwards to the arm's bridge (m/s, + opens).
JAW_COMMAND_TOPIC = 'command/jaw'
MODE_TOPIC = 'controller/mode'
HOLD_SERVICE = 'controller/hold'


def _twist_values(msg: TwistStamped) -> tuple[tuple[float, float, float],
                                               tuple[float, float, float], str, float]:
    """(linear, angular, frame_id, stamp_s) of a TwistStamped."""
    v, w = msg.twist.linear, msg.twist.angular
    stamp = msg.header.stamp
    return ((v.x, v.y, v.z), (w.x, w.y, w.z), msg.header.frame_id,
            stamp.sec + stamp.nanosec * 1e-9)


class ControllerPilot:
    """Pilot methods of the controller node (a mixin of ``ControllerNode``)."""

    supervisor: Any
    core: Any
    _entities: list[Any]
    _active: bool
    _diagnostics: Any
    pilot: PilotHandover | None

    def _declare_pilot(self, robot: Any) -> None:
        """Declare ``pilot.*`` (robot folder defaults) and the mode's latched publisher."""
        self._pilot_values = declare_parameters(self, PILOT_PARAMETER_SPECS, robot)  # type: ignore[arg-type]
        self.pilot = None
        self._refusals = RefusalLog()
        self._switches = 0
        self._last_switch = 'mode hold: started'
        self._script: ScriptPlayer | None = None

    def _configure_pilot(self) -> None:
        """Build the hand-over on the supervisor; subscribe the pilot, serve hold, read the script.

        Raises:
            ControlParameterError: a pilot limit or the script is invalid.
        """
        node: Any = self
        limits = PilotLimits.from_parameters(self._pilot_values)
        commands = load_script_text(str(self._pilot_values['pilot.script']))
        self.pilot = PilotHandover(self.supervisor, limits)
        self._script = ScriptPlayer(commands) if commands else None
        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self._mode_pub = node.create_publisher(String, MODE_TOPIC, latched)
        self._jaw_pub = node.create_publisher(Float64, JAW_COMMAND_TOPIC, qos)
        self._jaw_sent = 0.0
        self._entities += [
            (node.destroy_publisher, self._mode_pub),
            (node.destroy_publisher, self._jaw_pub),
            (node.destroy_subscription, node.create_subscription(
                TwistStamped, VEHICLE_TOPIC, self._on_pilot_vehicle, qos)),
            (node.destroy_subscription, node.create_subscription(
                TwistStamped, EE_TOPIC, self._on_pilot_ee, qos)),
            (node.destroy_subscription, node.create_subscription(
                Float64, JAW_TOPIC, self._on_pilot_jaw, qos)),
            (node.destroy_service, node.create_service(Trigger, HOLD_SERVICE, self._on_hold)),
        ]
        if commands:
            node.get_logger().info(f'pilot script: {len(commands)} timed command(s)')

    def _activate_pilot(self) -> None:
        """After activation: forget the pilot (hold) and latch the mode."""
        if self.pilot is not None:
            self.pilot.reset()
            self.pilot.take_switches()
            self.pilot.mode = PilotMode.HOLD
        self._publish_mode('hold')

    def _publish_mode(self, mode: str) -> None:
        msg = String()
        msg.data = mode
        self._mode_pub.publish(msg)

    # ------------------------------------------------------------------ the step

    def _pilot_before_step(self, t_ns: int) -> None:
        """Play the script's commands due now, then the hand-over; log and publish switches.

        Then ``command/jaw``: the jaw speed of this step (zero unless the pilot drives).
        """
        pilot = self.pilot
        if pilot is None:
            return
        t = t_ns * 1e-9
        if self._script is not None:
            for command in self._script.due(t):
                self._play(t, command)
        pilot.before_step(t)
        node: Any = self
        for note in pilot.take_notes():
            node.get_logger().warn(note)
        switches = pilot.take_switches()
        for switch in switches:
            self._switches += 1
            self._last_switch = switch.line()
            node.get_logger().info(self._last_switch)
        if switches:
            self._publish_mode(pilot.mode.value)
            self._diagnostics.update()
        jaw = pilot.jaw_command_m_s()
        if jaw != 0.0 or self._jaw_sent != 0.0:  # a zero once, then quiet (no message a step)
            self._jaw_pub.publish(Float64(data=jaw))
            self._jaw_sent = jaw

    def _play(self, t: float, command: ScriptCommand) -> None:
        """One script command at t (s), through the checks a message takes."""
        assert self.pilot is not None
        if command.hold:
            ok, message = self.pilot.hold()
            self._log_hold(ok, message, 'pilot script')
            return
        zero = (0.0, 0.0, 0.0)
        if command.vehicle is not None:
            self._take('vehicle', 'pilot script vehicle', command.vehicle[:3],
                       command.vehicle[3:], '', t, t)
        if command.ee is not None:
            self._take('ee', 'pilot script ee', command.ee, zero, command.frame, t, t)
        if command.jaw is not None:
            self._take_jaw('pilot script jaw', command.jaw, t)

    # ------------------------------------------------------------------ inputs

    def _now_s(self) -> float:
        node: Any = self
        return float(node.get_clock().now().nanoseconds) * 1e-9

    @guarded('pilot/vehicle_twist callback')
    def _on_pilot_vehicle(self, msg: TwistStamped) -> None:
        linear, angular, frame, stamp = _twist_values(msg)
        self._take('vehicle', VEHICLE_TOPIC, linear, angular, frame, stamp, self._now_s())

    @guarded('pilot/ee_twist callback')
    def _on_pilot_ee(self, msg: TwistStamped) -> None:
        linear, angular, frame, stamp = _twist_values(msg)
        self._take('ee', EE_TOPIC, linear, angular, frame, stamp, self._now_s())

    @guarded('pilot/jaw callback')
    def _on_pilot_jaw(self, msg: Float64) -> None:
        self._take_jaw(JAW_TOPIC, float(msg.data), self._now_s())

    def _take(self, kind: str, topic: str, linear: Any, angular: Any, frame: str,
              stamp_s: float, now_s: float) -> None:
        """Check, bound and hand on one twist; refusals and clipping named once per topic."""
        pilot = self.pilot
        if pilot is None or not self._active:
            self._refused(topic, Refusal.INACTIVE,
                          f'{topic} ignored: the controller is not active')
            return
        limits = pilot.limits
        try:
            check_stamp(topic, stamp_s, now_s, limits.deadman_s)
            if kind == 'vehicle':
                twist = vehicle_twist(topic, linear, angular, frame, limits.vehicle_speed_m_s,
                                      limits.vehicle_rate_rad_s)
            else:
                twist = ee_twist(topic, linear, angular, frame, limits.ee_speed_m_s)
        except PilotInputError as error:
            self._refused(topic, error.kind, f'refused {error}')
            return
        if twist.clipped:
            self._refused(topic, Refusal.CLIPPED, (
                f'{topic}: {[*linear, *angular]} beyond the pilot limits (pilot.*): scaled '
                f'down to {[*twist.linear, *twist.angular]}'))
        if kind == 'vehicle':
            pilot.vehicle(now_s, twist)
        else:
            pilot.ee(now_s, twist)

    def _take_jaw(self, topic: str, speed: float, now_s: float) -> None:
        pilot = self.pilot
        if pilot is None or not self._active:
            return
        try:
            bounded, clipped = jaw_speed(topic, speed, pilot.limits.jaw_speed_m_s)
        except PilotInputError as error:
            self._refused(topic, error.kind, f'refused {error}')
            return
        if clipped:
            self._refused(topic, Refusal.CLIPPED, f'{topic}: {speed} m/s beyond '
                          f'pilot.max_jaw_speed_m_s: {bounded} m/s')
        pilot.jaw(now_s, bounded)

    def _refused(self, topic: str, kind: Refusal, message: str) -> None:
        if self._refusals.first(topic, kind):
            node: Any = self
            node.get_logger().warn(f'{message} (said once per topic; counted on /diagnostics)')

    @guarded('controller/hold callback')
    def _on_hold(self, request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        """Hold now: the pilot released (a task canceled as a cancel does)."""
        pilot = self.pilot
        if pilot is None or not self._active:
            response.success, response.message = False, 'the controller is not active'
            return response
        response.success, response.message = pilot.hold()
        self._log_hold(response.success, response.message, HOLD_SERVICE)
        return response

    def _log_hold(self, ok: bool, message: str, source: str) -> None:
        node: Any = self
        node.get_logger().info(f'{source}: hold {"done" if ok else "refused"}: {message}')

    # ------------------------------------------------------------------ report

    def _report_pilot(self) -> Report:
        """The owner, the last switch and the pilot input refused so far."""
        pilot = self.pilot
        mode = 'none' if pilot is None else pilot.mode.value
        refusal = None if pilot is None else pilot.refusal
        values = {'mode': mode, 'switches': self._switches, 'last_switch': self._last_switch,
                  'refused_inputs': self._refusals.summary() or 'none',
                  'last_refusal': refusal or 'none',
                  'script': 'none' if self._script is None
                  else f'{len(self._script.commands)} command(s)'}
        return Report(WARN if refusal else OK, self._last_switch, values)
