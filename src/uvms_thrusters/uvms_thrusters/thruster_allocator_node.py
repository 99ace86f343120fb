"""The ``thruster_allocator`` node: allocation (paper eq. 10) and thruster dynamics (eq. 11-15).

Subscribes ``command/generalized_force``; publishes ``command/actuators`` (actual thrusts
after the thruster dynamics, motor torques), ``thrusters/state`` and ``thrusters/health``
(thruster faults: injected on the thruster model, detected from its ESC feedback, allocated
around; ``core.thruster_faults``, ``core.fault_detection``, docs/controller.md). ``trigger_mode:
lockstep`` answers every command with its stamp, integrating the thrusters over the time
between command stamps; ``timer`` steps at ``rate_hz`` of the steady clock on the latest
command, stamped with the node clock. A rejected command (NaN/Inf, wrong size, frame or
joints) is logged and the last safe command is held;
in timer mode a command older than ``watchdog_timeout_s`` (node clock) is replaced by zero,
so the thrusters spin down and the motors go limp.

A managed node (``autostart``: it activates itself unless false). Configure validates the
parameters and builds the core; inactive, it commands zero thrust and zero joint torque: at
deactivation at once, then in answer to every lockstep command (stamped like it, so the
lockstep exchange never stalls) or at ``rate_hz`` in timer mode. Unconfigured, it publishes
nothing. ``/diagnostics`` reports the state, rates, input age, rejections and saturation.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Any

import numpy as np
from rclpy.clock import Clock, ClockType
from rclpy.exceptions import ParameterException
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rclpy.qos import QoSProfile, ReliabilityPolicy
from uvms_common.cdr_codecs import MalformedPayloadError
from uvms_common.clock_read import now_ns
from uvms_common.diagnostics import (
    ERROR,
    OK,
    WARN,
    DiagnosticsPublisher,
    RateMeter,
    Report,
    robot_name,
)
from uvms_common.exchange_qos import input_qos
from uvms_common.lifecycle import autostart, declare_autostart, guard_change_state, state_label
from uvms_common.node_construction import destroyed_if_construction_fails
from uvms_common.node_main import run_node
from uvms_common.rate_gate import RateGate
from uvms_common.raw_clock import take_clock_raw
from uvms_common.realtime import MISS_WINDOW_S, EventLogger, MissCounter, StalenessMonitor
from uvms_common.robot_parameters import (
    check_all_declared,
    declare_robot,
    robot_model_values,
    with_robot_source,
)
from uvms_common.unconfigured import allocator_zero_answer, answer_while_unconfigured
from uvms_model.thrusters import ThrusterLayout

from uvms_common import direct_topics
from uvms_model import PARAMETER_SPECS, ModelError, UvmsParameters, load_description
from uvms_msgs.msg import ActuatorCommand, GeneralizedForce, ThrusterHealth, ThrusterState
from uvms_thrusters import raw_conversions
from uvms_thrusters.allocation import AllocatorParameters, ThrusterAllocator
from uvms_thrusters.errors import ThrusterInputError, ThrusterParameterError
from uvms_thrusters.fault_parameters import FAULT_PARAMETER_SPECS, equip, fault_settings
from uvms_thrusters.health_conversions import (
    HEALTH_TOPIC,
    health_change,
    health_message,
    health_report,
    on_set_fault_parameters,
)
from uvms_thrusters.parameter_specs import ALLOCATOR_PARAMETER_SPECS
from uvms_thrusters.parameters import thruster_parameters_from_flat_dict, validate_node_parameters
from uvms_thrusters.ros_parameters import declare_parameters

SUCCESS = TransitionCallbackReturn.SUCCESS
FAILURE = TransitionCallbackReturn.FAILURE


class ThrusterAllocatorNode(LifecycleNode):
    """Generalized force command in, thrusts and motor torques out."""

    @destroyed_if_construction_fails
    def __init__(self, **kwargs: Any) -> None:
        """Declare the parameters and, under ``autostart``, configure and activate.

        Raises:
            ThrusterParameterError: A parameter of the wrong type or, under ``autostart``, one
                that configure refused (named, with its value and valid range).
        """
        super().__init__('thruster_allocator', **kwargs)
        self._clock_source = take_clock_raw(self)  # /clock raw under use_sim_time
        self.robot_name, robot = declare_robot(self)
        self._robot_files = robot
        self._robot = robot_model_values(declare_parameters(self, PARAMETER_SPECS, robot),
                                         self.robot_name)
        self._values = declare_parameters(self, ALLOCATOR_PARAMETER_SPECS, robot)
        self._fault_values = declare_parameters(self, FAULT_PARAMETER_SPECS, robot)
        check_all_declared(self, robot)
        self.add_on_set_parameters_callback(self._on_set_fault_parameters)
        guard_change_state(self)
        starting = declare_autostart(self)
        self.core: ThrusterAllocator | None = None
        self._entities: list[tuple[Callable[[Any], Any], Any]] = []  # (destroy, entity)
        self._active = False
        self._transition_error: Exception | None = None
        self._log_transition_errors = not starting  # under autostart the constructor raises it
        # Counters for /diagnostics (since start; the report turns them into rates).
        self._published = self._saturated = self._rejected = 0
        self._meters = {name: RateMeter() for name in ('published', 'saturated', 'rejected')}
        self._diagnostics = DiagnosticsPublisher(self)
        self._diagnostics.add('allocation', self._report)
        answer_while_unconfigured(self, self._values['trigger_mode'] == 'lockstep', not starting,
                                  lambda: allocator_zero_answer(self, self._robot))
        self._diagnostics.add('thruster health', lambda: health_report(self.core))
        if starting and not autostart(self):
            error = self._transition_error or RuntimeError('autostart failed (see the log)')
            self.destroy_node()
            raise error
        self._log_transition_errors = True

    # ------------------------------------------------------------------------ lifecycle

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Validate the parameters, build the core, create publishers, subscription, timer."""
        try:
            self._configure()
        except Exception as error:  # rclpy would turn it into ERROR silently
            self._release()
            return self._failed('configure', error)
        return SUCCESS

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Start allocating from rest: thrusters at zero speed, no command held yet."""
        if self.core is None:
            return self._failed('activate', RuntimeError('no allocator core: not configured'))
        self.core.reset()
        self._safe_tau_b = np.zeros_like(self._safe_tau_b)
        self._last_stamp_ns = self._arrival_ns = None
        self._stale = False
        self._staleness = StalenessMonitor()  # a start-up grace from each activation
        self._active = True
        return super().on_activate(state)

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Command zero thrust and zero joint torque at once; zeros until reactivated."""
        self._active = False
        self._publish_zero(self.get_clock().now().nanoseconds)
        return super().on_deactivate(state)

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Drop the core, the publishers, the subscription and the timer."""
        self._release()
        return super().on_cleanup(state)

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        """From any state: zero command if it was active, then release everything."""
        return self._safe_stop(state, super().on_shutdown)

    def on_error(self, state: LifecycleState) -> TransitionCallbackReturn:
        """A transition raised: zero command, release everything, back to unconfigured."""
        return self._safe_stop(state, super().on_error)

    def destroy_node(self) -> None:
        """Shut down (zero command if active) as rclcpp's lifecycle node does, then destroy."""
        if state_label(self) in ('unconfigured', 'inactive', 'active') and self.context.ok():
            self.trigger_shutdown()
        self._diagnostics.destroy()
        super().destroy_node()

    def _configure(self) -> None:
        values = validate_node_parameters(ALLOCATOR_PARAMETER_SPECS, self._values)
        # Seconds of silence otherwise (the URDF, the kernels from Numba's cache).
        self.get_logger().info('loading the thruster model and compiled kernels')
        try:
            uvms = UvmsParameters.from_flat_dict(self._robot)
            layout = ThrusterLayout.from_parameters(uvms.thrusters)
            description = load_description(
                uvms.description.urdf_path, uvms.description.hydrodynamics_path
            )
        except ModelError as error:
            raise ThrusterParameterError(
                'robot parameters', with_robot_source(str(error), self._robot_files),
                f'valid values (robot {self.robot_name!r})'
            ) from error
        joint_names = description.joint_names
        thruster = thruster_parameters_from_flat_dict(
            {k: v for k, v in values.items() if k.startswith('thruster.')},
            uvms.hydrodynamics.water_density_kg_m3,
        )
        torque_limits = np.asarray(values['allocator.max_joint_torque_n_m'], dtype=float)
        if torque_limits.size != len(joint_names):
            raise ThrusterParameterError(
                'allocator.max_joint_torque_n_m',
                torque_limits.tolist(),
                f'{len(joint_names)} values, one per arm joint',
            )
        limits = AllocatorParameters(
            layout.thrust_matrix(), layout.max_thrust_n, torque_limits, thruster
        )
        self.core = ThrusterAllocator(limits)
        faults = fault_settings(self._fault_values, layout.count)
        equip(self.core, faults)  # injection (plant side), ESC telemetry, detection
        self._diagnostics.hardware_id = robot_name(description.urdf_text)
        self._joint_names = joint_names
        self._trigger_mode = str(values['trigger_mode'])
        self._desired_output = values['thruster_output'] == 'desired'
        self._lockstep = self._trigger_mode == 'lockstep'
        self._watchdog_ns = round(float(values['watchdog_timeout_s']) * 1e9)
        self._max_step_ns = round(float(values['max_step_s']) * 1e9)
        self._period_s = 1.0 / float(values['rate_hz'])
        self._safe_tau_b = np.zeros(6 + len(self._joint_names))
        self._zero_thrust = np.zeros(layout.count)
        self._zero_torque = np.zeros(len(self._joint_names))
        self._last_stamp_ns: int | None = None
        self._arrival_ns: int | None = None
        self._stale = False
        # Timer mode: a command missing or stale during start-up is INFO; missed periods
        # are counted on the steady clock the timer runs on.
        self._staleness = StalenessMonitor()
        self._steady = Clock(clock_type=ClockType.STEADY_TIME)
        self._misses = MissCounter(round(self._period_s * 1e9))
        # Command-triggered steps: commands left out, counted on their stamps, for the
        # process's figures (diagnostics, uvms launch's table).
        self._answered = MissCounter(round(self._period_s * 1e9))
        self._staleness_log = EventLogger(self.get_logger(), {
            'waiting': 'waiting for fresh generalized force commands (start-up): thrusters '
                       'and motors set to zero',
            'fresh': 'fresh generalized force commands: allocating',
            'stale': 'generalized force command is stale: thrusters and motors set to zero',
            'never_fresh': 'no generalized force command since start-up: thrusters and '
                           'motors set to zero',
            'resumed': 'fresh generalized force commands: resumed'})
        # Raw CDR through the robot's fixed layouts (uvms_thrusters.raw_conversions).
        self._actuator_writer = raw_conversions.ActuatorCommandWriter(layout.count, joint_names)
        self._state_writer = raw_conversions.ThrusterStateWriter(layout.count)
        self._reader = raw_conversions.generalized_force_reader(joint_names)

        # Plain publishers, not lifecycle ones: inactive, the node still commands zero.
        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        self._actuator_pub = self.create_publisher(ActuatorCommand, 'command/actuators', qos)
        self._state_pub = self.create_publisher(ThrusterState, 'thrusters/state', qos)
        self._state_gate = RateGate(float(values['state_rate_hz']))
        self._health_pub = self.create_publisher(ThrusterHealth, HEALTH_TOPIC, qos)
        self._health_gate = RateGate(faults.health_rate_hz)
        self._health_msg: ThrusterHealth | None = None
        self._health_key: tuple[Any, ...] | None = None
        self._entities = [
            (self.destroy_publisher, self._actuator_pub),
            (self.destroy_publisher, self._state_pub),
            (self.destroy_publisher, self._health_pub),
            direct_topics.subscribe(
                self, GeneralizedForce, 'command/generalized_force', self._on_command,
                input_qos(self._lockstep), raw=True)]
        if not self._lockstep:
            # On the steady clock, as the controller's: /clock bursts must not drop periods.
            self._entities.append((self.destroy_timer, self.create_timer(
                self._period_s, self._on_timer, clock=Clock(clock_type=ClockType.STEADY_TIME))))
        c = self.core.thrusters.calibration
        self.get_logger().info(
            f'{layout.count} thrusters, {values["trigger_mode"]} trigger; calibrated blade area '
            f'{c.blade_area:.4g} m^2, reverse lift factor {c.reverse_lift_factor:.3f}, '
            f'integration step <= {c.max_step * 1e3:.3g} ms'
        )

    def _release(self) -> None:
        """Destroy what configure created (the timer, subscription, publishers) and the core."""
        self._active = False
        for destroy, entity in reversed(self._entities):
            destroy(entity)
        self._entities = []
        self.core = None

    def _failed(self, transition: str, error: Exception) -> TransitionCallbackReturn:
        """Keep the error for the constructor, or log it: a transition never fails silently."""
        self._transition_error = error
        if self._log_transition_errors:
            reason = str(error) if isinstance(error, ThrusterParameterError) else (
                f'{type(error).__name__}: {error}')
            self.get_logger().error(f'{transition} failed: {reason}')
        return FAILURE

    def _safe_stop(self, state: LifecycleState, then: Any) -> TransitionCallbackReturn:
        try:
            if self._active:
                self._publish_zero(self.get_clock().now().nanoseconds)
            self._release()
        except Exception as error:  # rclpy would turn it into ERROR silently
            return self._failed('shutdown', error)
        return then(state)  # type: ignore[no-any-return]

    # ------------------------------------------------------------------------ callbacks

    def _on_command(self, data: bytes) -> None:
        """Keep a valid command; in lockstep answer it at once with its own stamp."""
        try:
            decoded = self._reader.decode(data)
        except MalformedPayloadError as error:
            self._rejected += 1
            self.get_logger().error('malformed generalized force payloads (counted on '
                                    f'/diagnostics), first: {error}', once=True)
            return
        stamp = decoded.stamp_ns
        if not self._active:
            if self._lockstep:
                self._publish_zero(stamp)
            return
        try:
            tau_b = self._reader.value(decoded)
        except ThrusterInputError as error:
            self._rejected += 1
            self.get_logger().error(
                f'rejected generalized force, holding the last safe command: {error}',
                throttle_duration_sec=1.0,
            )
            tau_b = None
        now = now_ns(self.get_clock())  # one read for the arrival and the lockstep check
        if tau_b is not None:
            self._safe_tau_b = tau_b
            self._arrival_ns = now
        if not self._lockstep:
            return
        if self._last_stamp_ns is not None and stamp < self._last_stamp_ns:
            return  # an old command: the thrusters are already past it
        ahead_ns = stamp - now
        if ahead_ns > self._max_step_ns:
            # Stamped beyond simulated time: no state asked for it (another publisher). It
            # must not move the thruster time ahead, or the real commands would look old.
            self.get_logger().warn(
                f'ignored generalized force stamped {ahead_ns * 1e-9:.3f} s ahead of the clock',
                throttle_duration_sec=1.0,
            )
            return
        dt_ns = 0 if self._last_stamp_ns is None else stamp - self._last_stamp_ns
        if dt_ns > self._max_step_ns:
            self.get_logger().warn(
                f'{dt_ns * 1e-9:.3f} s between commands exceeds max_step_s: thrusters restarted'
            )
            assert self.core is not None
            self.core.reset()
            dt_ns = 0
        self._last_stamp_ns = stamp
        self._step(stamp, self._safe_tau_b, dt_ns * 1e-9)
        self._answered.tick(stamp)

    def _on_timer(self) -> None:
        """Timer mode: step on the latest command, or on zero once it is stale or inactive."""
        now = self.get_clock().now().nanoseconds
        if not self._active:
            self._publish_zero(now)
            return
        tau_b = self._safe_tau_b
        stale = self._arrival_ns is None or now - self._arrival_ns > self._watchdog_ns
        self._staleness_log.log(self._staleness.observe(now, stale))
        self._stale = self._staleness.alarmed
        if stale:
            tau_b = np.zeros_like(tau_b)
        self._step(now, tau_b, self._period_s)
        share = self._misses.tick(self._steady.now().nanoseconds)
        if share is not None:
            self.get_logger().warning(
                f'missed {share:.1%} of the allocation periods in the last {MISS_WINDOW_S:g} s '
                '(late timer: the machine is busy)')

    def _step(self, t_ns: int, tau_b: np.ndarray, dt: float) -> None:
        assert self.core is not None
        output = self.core.step(tau_b, dt, t_ns * 1e-9)
        for fault in self.core.injector.newly_started(t_ns * 1e-9):
            self.get_logger().warning(
                f'fault injected at {t_ns * 1e-9:.3f} s: {fault.describe()} (simulated: '
                f"fault_injection.thrusters, a scenario's faults:); the allocator knows it "
                'only from the ESC feedback')
        self._published += 1
        self._saturated += output.allocation.saturation_scale < 1.0
        # 'desired' (hardware): the real thrusters follow what is sent, so an injected fault
        # acts by sending its demand (a stuck thruster's thrust; none: the allocation's).
        thrust = (self.core.injector.motor_demand(output.allocation.thrust, t_ns * 1e-9)
                  if self._desired_output else output.thrust)
        self._actuator_pub.publish(
            self._actuator_writer.payload(t_ns, thrust, output.joint_torques))
        if self._state_gate.due(t_ns):
            self._state_pub.publish(self._state_writer.payload(t_ns, output))
        self._publish_health(t_ns, output)

    def _publish_health(self, t_ns: int, output: Any) -> None:
        """thrusters/health at its rate, and at once when a status or the rank changes."""
        assert self.core is not None
        detector = self.core.detector
        key = (self.core.rank, self.core.accommodate,
               None if detector is None else detector.status.tobytes(),
               None if detector is None else detector.settled.tobytes())
        if self._health_gate.due(t_ns) or key != self._health_key:
            change = health_change(self._health_key, key, self.core)  # one console line
            if change is not None and change[0] == ERROR:
                self.get_logger().error(change[1])
            elif change is not None:
                self.get_logger().warning(change[1])
            self._health_key = key
            self._health_msg = health_message(t_ns, self.core, output, self._health_msg)
            self._health_pub.publish(self._health_msg)

    def _on_set_fault_parameters(self, parameters: list[Any]) -> Any:
        """Faults injected and accommodation switched at run time (docs/controller.md)."""
        result = on_set_fault_parameters(getattr(self, 'core', None), parameters)
        if result.successful:
            self._fault_values.update({p.name: p.value for p in parameters
                                       if p.name in self._fault_values})
        return result

    def _publish_zero(self, t_ns: int) -> None:
        """Zero thrust and zero joint torque stamped t_ns (inactive, or leaving active)."""
        self._actuator_pub.publish(
            self._actuator_writer.payload(t_ns, self._zero_thrust, self._zero_torque))

    def _report(self) -> Report:
        """/diagnostics: lifecycle state, output rate, input age, rejections, saturation."""
        now_ns = self.get_clock().now().nanoseconds
        rates = {name: meter.rate_hz(getattr(self, f'_{name}'), now_ns)
                 for name, meter in self._meters.items()}
        state = state_label(self)
        values: dict[str, Any] = {'lifecycle_state': state}
        if self.core is None:
            return Report(WARN, f'{state}: publishes nothing', values)
        step_hz, saturated_hz = rates['published'], rates['saturated']
        age_s = None if self._arrival_ns is None else (now_ns - self._arrival_ns) * 1e-9
        values.update({
            'trigger_mode': self._trigger_mode, 'output_rate_hz': step_hz, 'input_age_s': age_s,
            'missed_periods': self._misses.missed, 'missed_share': self._misses.share,
            'rejected_commands': self._rejected, 'rejected_per_s': rates['rejected'],
            'malformed_commands': self._reader.decoder.malformed,
            'saturation_share': saturated_hz / step_hz if step_hz and saturated_hz is not None
            else None})
        if not self._active:
            return Report(WARN, f'{state}: commanding zero thrust and joint torque', values)
        if self._stale:
            return Report(WARN, 'command stale: zero thrust and joint torque', values)
        if rates['rejected']:
            return Report(WARN, 'rejecting generalized force commands', values)
        return Report(OK, 'running', values)


def main(args: list[str] | None = None) -> None:
    """Run the thruster allocator node until SIGINT/SIGTERM."""
    sys.exit(run_node(ThrusterAllocatorNode, args, 'thruster_allocator',
                      (ThrusterParameterError, ParameterException)))

if __name__ == '__main__':
    main()
