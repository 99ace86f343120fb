"""The ``controller`` node: the unified force controller (paper sec. 4), commanded by tasks.

Subscribes ``joint_states``, ``odometry``, ``wrench`` and ``controller/target_position``
(PointStamped, map_ned: a streamed hold target while no task runs); publishes
``command/generalized_force`` and ``controller/state``; serves the ContactTask action
``controller/contact_task`` (relative names: run it in ``/uvms``). ``trigger_mode:
lockstep`` computes once the three inputs with one stamp have arrived and stamps the
command alike; ``timer`` computes at ``control_rate_hz`` of the steady clock on the latest
inputs; ``odometry`` computes on each vehicle state (``odometry/filtered`` on the estimate)
with the latest joint states and wrench, stamped with the state's stamp. Rejected inputs are
logged; stale inputs (older than ``watchdog_timeout_s``, or a gap that long between two steps)
give a zero command, logged once, and end a running task INPUTS_STALE; so does an inactive
thruster allocator (``node_safety.AllocatorWatch``). Control resumes holding where it is.

A managed node (``autostart``: it activates itself unless false): configure builds the model
and the controller; activate resets the task supervisor (no target, no queued goal) and holds
the end effector where it is at the first step; deactivate ends running and queued tasks
INACTIVE and commands zero generalized force, in answer to every lockstep stamp (so the
exchange never stalls) or at the control rate. Gains, the contact threshold, null-space gains
and ``safety.*`` change at run time (checked whole, then ramped in); the rest is read-only.
No exception escapes a callback (``controller_safety``). ``/diagnostics``: rates, input ages,
rejections, faults, allocator and lifecycle state, the task, any safety limit reached. A
person pilots through ``pilot/vehicle_twist``, ``pilot/ee_twist`` and ``pilot/jaw``, the owner
on ``controller/mode``, ``controller/hold`` to stop (``controller_pilot``, docs/piloting.md).
``arm.hold_in_joint_space`` holds the arm's joints while no task runs (``joint_hold``).
"""

from __future__ import annotations

import sys
from typing import Any

import numpy as np
from geometry_msgs.msg import PointStamped
from rclpy.clock import Clock, ClockType
from rclpy.exceptions import ParameterException
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rclpy.qos import QoSProfile, ReliabilityPolicy
from uvms_common.cdr_codecs import MalformedPayloadError
from uvms_common.clock_read import now_ns, steady_ns
from uvms_common.diagnostics import DiagnosticsPublisher, RateMeter
from uvms_common.exchange_qos import input_qos
from uvms_common.lifecycle import autostart, declare_autostart, guard_change_state, state_label
from uvms_common.node_construction import destroyed_if_construction_fails
from uvms_common.node_main import run_node
from uvms_common.rate_gate import RateGate
from uvms_common.raw_clock import take_clock_raw
from uvms_common.realtime import MISS_WINDOW_S, EventLogger, MissCounter, StalenessMonitor
from uvms_common.unconfigured import answer_while_unconfigured, controller_zero_answer

from uvms_common import direct_topics
from uvms_common import robot_parameters as robots
from uvms_control import raw_conversions, task_conversions
from uvms_control.controller_pilot import ControllerPilot
from uvms_control.controller_reports import ControllerReports
from uvms_control.controller_safety import ControllerSafety, safety_limits
from uvms_control.core.errors import ControlInputError, ControlParameterError
from uvms_control.core.law.held_command import held_slot_horizon_s
from uvms_control.core.law.task_path import load_interpolation
from uvms_control.core.law.unified_controller import UnifiedForceController
from uvms_control.core.parameter_specs import (
    CONTROLLER_NODE_PARAMETER_SPECS,
    CONTROLLER_PARAMETER_SPECS,
    SAFETY_PARAMETER_SPECS,
)
from uvms_control.core.parameters import ControllerParameters, topic_for, validate_node_parameters
from uvms_control.core.pilot.supervisor import PilotedSupervisor
from uvms_control.core.task.contact_task import TaskCode, TaskGoalError
from uvms_control.core.task.joint_hold import joint_hold_from
from uvms_control.core.task.task_supervisor import TaskSupervisor
from uvms_control.node_safety import AllocatorWatch, FaultLog, guarded
from uvms_control.pending_stamps import Input, PendingStamps
from uvms_control.ros_parameters import declare_parameters
from uvms_control.task_server import ContactTaskServer
from uvms_model import PARAMETER_SPECS, ModelError, UvmsModel, UvmsParameters
from uvms_msgs.msg import ControllerState, GeneralizedForce

TOPICS = ('joint_states', 'odometry', 'wrench')
SUCCESS = TransitionCallbackReturn.SUCCESS
FAILURE = TransitionCallbackReturn.FAILURE


class ControllerNode(ControllerReports, ControllerSafety, ControllerPilot, LifecycleNode):
    """Unified force controller: sensor topics and tasks in, generalized force and state out."""

    @destroyed_if_construction_fails
    def __init__(self, **kwargs: Any) -> None:
        """Declare the parameters and, under ``autostart``, configure and activate.

        Raises:
            ControlParameterError: a parameter that configure refused, under ``autostart``.
        """
        super().__init__('controller', **kwargs)
        self._clock_source = take_clock_raw(self)  # /clock raw under use_sim_time
        self.robot_name, robot = robots.declare_robot(self)
        self._robot_files = robot
        self._robot = robots.robot_model_values(declare_parameters(self, PARAMETER_SPECS, robot),
                                                self.robot_name)
        self._node_values = declare_parameters(self, CONTROLLER_NODE_PARAMETER_SPECS, robot)
        self._gains = declare_parameters(self, CONTROLLER_PARAMETER_SPECS, robot)
        self._safety = declare_parameters(self, SAFETY_PARAMETER_SPECS, robot)
        self._declare_pilot(robot)
        robots.check_all_declared(self, robot)
        starting = declare_autostart(self)
        guard_change_state(self)
        self.core: UnifiedForceController | None = None
        self.supervisor: TaskSupervisor | None = None
        self._active = False
        self._entities: list[Any] = []
        self._error: Exception | None = None
        self._joint_names: list[str] = []
        self._inputs: dict[str, Input | None] = dict.fromkeys(TOPICS)
        self._pending = PendingStamps(TOPICS)
        self._counts = {'steps': 0, 'rejected': 0, 'zeroed': 0, 'malformed': 0}
        self._faults = FaultLog(self.get_logger())
        self._allocator: AllocatorWatch | None = None
        self._halted: str | None = None  # why control stopped (stale, allocator); None: runs
        self._rate = RateMeter()
        self._breach: str | None = None
        self._stale = False
        self._staleness = StalenessMonitor()
        self._misses: MissCounter | None = None
        self.add_on_set_parameters_callback(self._on_set_parameters)
        self.tasks = ContactTaskServer(self, lambda: self.supervisor if self._active else None,
                                       lambda: self.get_clock().now().nanoseconds * 1e-9,
                                       on_error=self._fault)
        self.create_subscription(PointStamped, 'controller/target_position', self._on_target,
                                 QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE))
        self._diagnostics = DiagnosticsPublisher(self, self._hardware_id())
        self._diagnostics.add('control', self._report_control)
        self._diagnostics.add('task', self._report_task)
        self._diagnostics.add('pilot', self._report_pilot)
        answer_while_unconfigured(self, self._node_values['trigger_mode'] == 'lockstep',
                                  not starting, lambda: controller_zero_answer(self))
        if starting and not autostart(self):
            error = self._error or ControlParameterError('autostart', True, 'a node that can '
                                                         'configure and activate')
            self.destroy_node()
            raise error

    # ------------------------------------------------------------------------ lifecycle

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Validate the parameters, build model, controller, task supervisor and topics."""
        try:
            node = validate_node_parameters(CONTROLLER_NODE_PARAMETER_SPECS, self._node_values)
            gains = ControllerParameters.from_flat_dict(self._gains)
            # Seconds of silence otherwise (URDF, Pinocchio, the kernels from Numba's cache).
            self.get_logger().info('loading the model and compiled kernels')
            load_interpolation()  # the paths' splines, before the loop (not at the first goal)
            try:
                model = UvmsModel(UvmsParameters.from_flat_dict(self._robot))
            except ModelError as error:
                text = robots.with_robot_source(str(error), self._robot_files)
                raise ControlParameterError('robot parameters', text,
                                            f'robot {self.robot_name!r}') from error
            self.core = UnifiedForceController(
                gains, model, 1.0 / float(node['control_rate_hz']),
                held_slot_horizon_s(float(node['arm.command_rate_hz']),
                                    float(node['arm.force_latency_s'])))
            self.supervisor = PilotedSupervisor(self.core, safety_limits(self._safety),
                                                joint_hold_from(node))
            self._configure_topics(node, model.joint_names)
            self._configure_pilot()
            self._watch_allocator(str(node['allocator_node']))
        except Exception as error:  # rclpy would turn it into ERROR silently
            self._release()
            return self._failed('configure', error)
        self.get_logger().info(
            f'unified force controller, {node["trigger_mode"]} trigger, null space '
            f'{"on" if gains.null_space_enabled else "off"}, W mode {gains.switch_mode}; '
            'contact tasks on controller/contact_task')
        return SUCCESS

    def _configure_topics(self, node: dict[str, Any], joint_names: list[str]) -> None:
        self._joint_names = joint_names
        self._lockstep = node['trigger_mode'] == 'lockstep'
        self._on_odometry = node['trigger_mode'] == 'odometry'
        self._watchdog_ns = round(float(node['watchdog_timeout_s']) * 1e9)
        self._last_tau_b = np.zeros(len(joint_names) + 6)
        self._last_stamp_ns, self._zeroed_stamp_ns = -1, -1
        self._first_stamp_ns: int | None = None
        self._stale = False
        # Timer mode: start-up staleness is INFO (nodes start one after the other); missed
        # periods are counted on the steady clock the timer runs on.
        self._staleness = StalenessMonitor()
        self._steady = Clock(clock_type=ClockType.STEADY_TIME)
        self._misses = MissCounter(round(1e9 / float(node['control_rate_hz'])))
        self._period_ns = self._misses.period_ns
        # Input-triggered steps (lockstep, odometry): the states left unanswered, counted on
        # their stamps, for the process's figures (diagnostics, uvms launch's table).
        self._answered = MissCounter(round(1e9 / float(node['control_rate_hz'])))
        self._staleness_log = EventLogger(self.get_logger(), {
            'waiting': 'waiting for fresh joint_states, odometry and wrench (start-up): '
                       'publishing zero generalized force',
            'fresh': 'fresh inputs: control running',
            'stale': 'inputs older than watchdog_timeout_s: publishing zero generalized force',
            'never_fresh': 'no fresh inputs since start-up: publishing zero generalized force',
            'resumed': 'fresh inputs: control resumed'})
        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        inputs = input_qos(self._lockstep)  # deep in lockstep: foreign inputs cannot evict ours
        self._command_pub = self.create_publisher(GeneralizedForce, 'command/generalized_force',
                                                  qos)
        self._state_pub = self.create_publisher(ControllerState, 'controller/state', qos)
        self._state_gate = RateGate(float(node['state_rate_hz']))
        self._entities = [(self.destroy_publisher, self._command_pub),
                          (self.destroy_publisher, self._state_pub)]
        self._command_writer = raw_conversions.GeneralizedForceWriter(joint_names)
        self._state_writer = raw_conversions.ControllerStateWriter()
        for topic, (msg_type, read) in raw_conversions.controller_readers(joint_names).items():
            self._entities.append(direct_topics.subscribe(
                self, msg_type, topic_for(topic, str(node['state_source'])),
                lambda data, t=topic, r=read: self._on_input(t, r, data), inputs, raw=True))
        if node['trigger_mode'] == 'timer':
            # The period runs on the steady clock: a timer on /clock time fires once per
            # /clock message at most, so a burst of /clock drops control periods.
            self._entities.append((self.destroy_timer, self.create_timer(
                1.0 / float(node['control_rate_hz']), self._on_timer,
                clock=Clock(clock_type=ClockType.STEADY_TIME))))

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Reset the supervisor (no target, no goal); hold the end effector where it is next."""
        assert self.core is not None and self.supervisor is not None
        self.core.reset()
        self.tasks.finish(self.supervisor.reset())
        self._halted = None
        self._active = True
        result = super().on_activate(state)
        self._activate_pilot()
        return result

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """End running and queued tasks INACTIVE, drop the target, command zero."""
        self._active = False
        if self.supervisor is not None:
            self.tasks.finish(self.supervisor.abort_all(TaskCode.INACTIVE,
                                                        'the controller was deactivated'))
            self.tasks.finish(self.supervisor.reset())
        self._zero(self.get_clock().now().nanoseconds, None)
        return super().on_deactivate(state)

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Drop the controller, its publishers, subscriptions and timer."""
        self._release()
        return super().on_cleanup(state)

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        """From any state: zero command if it was active, end tasks, release everything."""
        if self._active:
            self._zero(self.get_clock().now().nanoseconds, None)
        self.tasks.finish_all(TaskCode.INACTIVE, 'the controller shut down')
        self._release()
        return super().on_shutdown(state)

    def destroy_node(self) -> None:
        """Shut down as rclcpp's lifecycle node does, then destroy."""
        if state_label(self) not in ('finalized', 'unknown') and self.context.ok():
            self.trigger_shutdown()
        self._diagnostics.destroy()
        self.tasks.destroy()
        super().destroy_node()

    def _release(self) -> None:
        self._active = False
        self._allocator = None
        for destroy, entity in reversed(self._entities):
            destroy(entity)
        self._entities = []
        self.core = self.supervisor = self.pilot = None

    def _failed(self, transition: str, error: Exception) -> TransitionCallbackReturn:
        self._error = error
        reason = (str(error) if isinstance(error, ControlParameterError)
                  else f'{type(error).__name__}: {error}')
        self.get_logger().error(f'{transition} failed: {reason}')
        return FAILURE

    # ------------------------------------------------------------------------ inputs

    @guarded('input callback')
    def _on_input(self, topic: str, reader: raw_conversions.Reader, data: bytes) -> None:
        """Convert and keep one input; in lockstep, compute once a stamp is complete."""
        try:
            decoded = reader.decode(data)
        except MalformedPayloadError as error:
            self._counts['rejected'] += 1
            self._counts['malformed'] += 1
            self.get_logger().error(f'malformed input payloads (counted on /diagnostics), '
                                    f'first on {topic}: {error}', once=True)
            return
        stamp = decoded.stamp_ns
        try:
            value = reader.value(decoded)
        except ControlInputError as error:
            self._counts['rejected'] += 1
            self.get_logger().error(f'rejected {topic}: {error}', throttle_duration_sec=1.0)
            value = None
        if not self._lockstep:
            if value is not None:  # timer and odometry modes compute on the last valid input
                now = now_ns(self.get_clock())
                self._inputs[topic] = Input(stamp, now, value)
                if self._on_odometry and topic == 'odometry':
                    self._step_on_latest(stamp, now)
            return
        entry = self._pending.arrive(stamp, topic, value)
        if value is not None:
            self._inputs[topic] = Input(stamp, 0, value)
            if self._first_stamp_ns is None:
                self._first_stamp_ns = stamp
        if entry.complete:
            self._pending.finish(stamp)
            self._compute(stamp, [Input(stamp, 0, entry.values[name]) for name in TOPICS])
            self._answered.tick(stamp)
            return
        if value is None or self._first_stamp_ns is None:
            return  # only valid inputs move the lockstep exchange on
        oldest = min(self._first_stamp_ns if i is None else i.stamp_ns
                     for i in self._inputs.values())
        if stamp - oldest > self._watchdog_ns and stamp != self._zeroed_stamp_ns:
            self._zeroed_stamp_ns = stamp  # answer the stamp once, so the simulation goes on
            self._zero(stamp, 'an input is older than watchdog_timeout_s')

    @guarded('control timer')
    def _on_timer(self) -> None:
        """Timer mode: compute on the latest inputs, or zero the command when they are stale."""
        now = self.get_clock().now().nanoseconds
        steps = self._counts['steps']
        inputs = [self._inputs[name] for name in TOPICS]
        if any(i is None for i in inputs):
            self.get_logger().info('waiting for joint_states, odometry and wrench', once=True)
        elif self._checked_fresh(now, inputs):
            self._compute(now, inputs)
        assert self._misses is not None
        ran = self._counts['steps'] > steps or not self._active
        share = self._misses.tick(self._steady.now().nanoseconds, ran)
        if share is not None:
            self.get_logger().warning(
                f'missed {share:.1%} of the control periods in the last {MISS_WINDOW_S:g} s '
                '(no new state published: late timer or no new simulated time)')

    def _step_on_latest(self, stamp: int, now: int) -> None:
        """Odometry mode: one step per vehicle state, on the latest joint states and wrench.

        In real time the estimate reaches the controller a hop after the state it is stamped
        with (simulator, estimator, controller); a step per estimate answers each state the
        estimator answered, once, with no beat against a timer and nothing waiting for a
        stamp that may not come (``docs/running.md``).
        """
        inputs = [self._inputs[name] for name in TOPICS]
        if any(i is None for i in inputs):
            self.get_logger().info('waiting for joint_states and wrench', once=True)
        elif self._checked_fresh(now, inputs):
            self._compute(stamp, inputs)
            self._answered.tick(stamp)

    def _checked_fresh(self, now: int, inputs: list[Input | None]) -> bool:
        """Timer mode: whether the inputs are fresh; zero command and log when not."""
        stale = any(now - i.arrival_ns > self._watchdog_ns for i in inputs if i is not None)
        self._staleness_log.log(self._staleness.observe(now, stale))
        if stale:
            self._zero(now, None)
            self._halt('inputs older than watchdog_timeout_s')
        return not stale

    @guarded('target_position callback')
    def _on_target(self, msg: PointStamped) -> None:
        """A streamed hold target: taken while no task runs, else refused with a log line."""
        try:
            target = task_conversions.target_position(msg)
        except TaskGoalError as error:
            self.get_logger().error(f'rejected target_position: {error}',
                                    throttle_duration_sec=1.0)
            return
        if self.supervisor is None or not self._active:
            self.get_logger().warn('target_position ignored: the controller is not active',
                                   throttle_duration_sec=5.0)
        elif not self.supervisor.set_target(target):
            self.get_logger().warn(f'{self.supervisor.refusal}', throttle_duration_sec=5.0)

    # ------------------------------------------------------------------------ control

    def _compute(self, t_ns: int, inputs: list[Input | None]) -> None:
        if not self._active or self.supervisor is None:
            self._publish_command(t_ns, np.zeros_like(self._last_tau_b))  # inactive: zero
            return
        if any(i is None or i.value is None for i in inputs):
            self._publish_command(t_ns, self._last_tau_b)  # hold the last safe command
            return
        if self._stale:
            self._stale = False
            self.get_logger().info('fresh inputs: control resumed')
        if t_ns == self._last_stamp_ns:
            self._publish_command(t_ns, self._last_tau_b)  # a re-published state: same answer
            return
        if not self._may_step(t_ns):
            return
        (positions, velocities), (eta, nu), force = (i.value for i in inputs if i is not None)
        t = t_ns * 1e-9
        try:
            self._pilot_before_step(t_ns)
            result, events = self.supervisor.step(
                t, np.concatenate((eta, positions)), np.concatenate((nu, velocities)), force,
                inputs[2].stamp_ns * 1e-9 if inputs[2] is not None else None)
        except ControlInputError as error:
            self.get_logger().error(f'control step failed, holding: {error}',
                                    throttle_duration_sec=1.0)
            self._publish_command(t_ns, self._last_tau_b)
            return
        except Exception as error:  # nothing escapes: zero command, tasks ended, logged
            self._fault('control step', error, t_ns)
            return
        self._counts['steps'] += 1
        self._last_tau_b = result.tau_b
        self._last_stamp_ns = t_ns
        self._publish_command(t_ns, result.tau_b)
        self.tasks.count_step(t_ns, steady_ns(), self._period_ns)
        if self._state_gate.due(t_ns):
            self._state_pub.publish(self._state_writer.payload(t_ns, result))
        self.tasks.finish(events)
        self.tasks.publish_feedback(self.supervisor, t)
        breach = self.supervisor.breach
        if self.supervisor.safe_hold and breach != self._breach:  # latched: said once
            self.get_logger().error(f'{breach}: goals are refused until `uvms lifecycle '
                                    f'{self.get_name()} reset` (deactivate, activate)')
        elif breach is not None and self._breach is None:  # once per breach, not per step
            self.get_logger().error(f'safety limit: {breach}')
        self._breach = breach

    def _zero(self, t_ns: int, reason: str | None) -> None:
        if reason is not None and not self._stale:
            self._stale = True
            self.get_logger().warn(f'{reason}: publishing zero generalized force')
            self._halt(reason)
        self._counts['zeroed'] += 1
        if self._entities:
            self._last_tau_b = np.zeros_like(self._last_tau_b)
            self._publish_command(t_ns, self._last_tau_b)

    def _publish_command(self, t_ns: int, tau_b: np.ndarray) -> None:
        self._command_pub.publish(self._command_writer.payload(t_ns, tau_b))


def main(args: list[str] | None = None) -> None:
    """Run the controller node until SIGINT/SIGTERM."""
    sys.exit(run_node(ControllerNode, args, 'controller',
                      (ControlParameterError, ParameterException)))


if __name__ == '__main__':
    main()
