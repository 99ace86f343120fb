"""The ``simulator`` node: integrates the UVMS plant and publishes its state and ``/clock``.

Lockstep (default): publish the state of step k stamped t_k, wait for the actuator command
stamped t_k, then integrate to the next publication; deterministic. Real time: a wall timer
integrates one step per period on the latest command. The node is the clock source, so it
keeps its own simulated time and never runs on ``use_sim_time``. ``/diagnostics`` reports the
achieved step rate, the real-time factor (both against the wall clock) and lockstep timeouts.
A `uvms_sim.plant_side.PlantSide` given to the node stands for the devices in its process.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Any

from geometry_msgs.msg import PoseStamped, WrenchStamped
from nav_msgs.msg import Odometry
from rclpy.exceptions import ParameterException
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import String
from tf2_msgs.msg import TFMessage
from uvms_common.cdr_codecs import MalformedPayloadError
from uvms_common.diagnostics import DiagnosticsPublisher, RateMeter, Report, robot_name
from uvms_common.exchange_qos import input_qos
from uvms_common.node_construction import destroyed_if_construction_fails
from uvms_common.node_main import run_node
from uvms_common.parameter_declaration import Spec, declare_specs
from uvms_common.realtime import MISS_WINDOW_S, STARTUP_GRACE_S, MissCounter
from uvms_common.robot_parameters import (
    check_all_declared,
    declare_robot,
    robot_model_values,
    robot_start_values,
    with_robot_source,
)
from uvms_model.nav_sensor_parameters import NAVIGATION_PARAMETER_SPECS, NavigationParameters

from uvms_model import PARAMETER_SPECS, ModelError, UvmsModel, UvmsParameters
from uvms_msgs.msg import ActuatorCommand, ContactState
from uvms_sim import conversions, raw_conversions
from uvms_sim.device_delivery import DeviceDelivery
from uvms_sim.errors import CommandError, SimParameterError, SimulationError
from uvms_sim.lockstep_wait import AttentiveWait
from uvms_sim.navigation_topics import NavigationTopics, dvl_mount
from uvms_sim.ocean_node import OceanCurrentInterface
from uvms_sim.parameters import (
    SIMULATOR_PARAMETERS,
    SimulatorSettings,
    default_joint_positions,
)
from uvms_sim.plant import Plant, initial_coordinates
from uvms_sim.plant_side import PlantSide, PlantSideNavigation
from uvms_sim.simulator_report import simulator_report
from uvms_sim.startup_hold import StartupHold
from uvms_sim.startup_watch import StartGates, StartupWatch, recorded_publishers

#: Most plant steps one real-time tick takes to catch up with the wall clock.
_MAX_CATCH_UP_STEPS = 10


def _parameter_error(spec: Spec, exc: ParameterException) -> SimParameterError:
    return SimParameterError(f'invalid parameter {spec.name!r}: {exc}')


class SimulatorNode(StartupHold):
    """Simulated UVMS: actuator commands in, sensor topics, ``/clock`` and ``/tf`` out."""

    @destroyed_if_construction_fails
    def __init__(self, plant_side: Callable[[SimulatorNode], PlantSide] | None = None,
                 **kwargs: Any) -> None:
        """Declare the parameters, build the plant and its topics.

        Args:
            plant_side: Builds the devices served in this process (given the node, once its
                parameters are declared and its plant built); None: the device-side topics.
            **kwargs: For rclpy's ``Node``.
        """
        super().__init__('simulator', **kwargs)
        if self.get_parameter('use_sim_time').value:
            msg = ("parameter 'use_sim_time' = True: the simulator publishes /clock and keeps "
                   'its own simulated time; valid: False')
            raise SimParameterError(msg)
        self.robot_name, files = declare_robot(self)
        robot = declare_specs(self, PARAMETER_SPECS, files, _parameter_error)
        values = declare_specs(self, SIMULATOR_PARAMETERS, files, _parameter_error)
        navigation = declare_specs(self, NAVIGATION_PARAMETER_SPECS, files, _parameter_error)
        check_all_declared(self, files)
        try:
            params = UvmsParameters.from_flat_dict(robot_model_values(robot, self.robot_name))
        except ModelError as exc:
            raise SimParameterError(
                with_robot_source(f'invalid robot parameter: {exc}', files)) from exc
        try:
            self._navigation_params = NavigationParameters.from_flat_dict(navigation)
        except ModelError as exc:
            raise SimParameterError(
                with_robot_source(f'invalid navigation parameter: {exc}', files)) from exc
        self._settings = cfg = SimulatorSettings.from_values(values)
        if plant_side is not None and cfg.mode == 'lockstep':
            raise SimParameterError("mode 'lockstep' with devices served in the simulator's "
                                    "process: they run on wall time; valid: 'realtime'")
        # Seconds of silence otherwise (URDF, Pinocchio, the kernels from Numba's cache).
        self.get_logger().info('loading the model and compiled kernels')
        model = UvmsModel(params)
        q0 = initial_coordinates(model, cfg.vehicle_pose,
                                 default_joint_positions(cfg.joint_positions, model.n_joints),
                                 cfg.ee_position if cfg.arm_from_ee_position else None,
                                 self.robot_name, robot_start_values(files))
        self._plant = Plant(params, q0, cfg.physics_dt_ns, cfg.wall_enabled,
                            cfg.wall_motion_start_force_n)
        self._plant_side = None if plant_side is None else plant_side(self)

        reliable = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        self._clock_pub = self.create_publisher(Clock, '/clock', reliable)
        self._joint_pub = self.create_publisher(JointState, 'joint_states', reliable)
        self._odom_pub = self.create_publisher(Odometry, 'odometry', reliable)
        self._wrench_pub = self.create_publisher(WrenchStamped, 'wrench', reliable)
        self._ee_pub = self.create_publisher(PoseStamped, 'ee_pose', reliable)
        self._contact_pub = self.create_publisher(ContactState, 'contact', reliable)
        # ocean.current.* (writable at run time) and ocean/current, at the ground-truth rate.
        self._ocean = OceanCurrentInterface(self, self._plant, reliable)
        self._tf_pub = self._static_tf_pub = None
        if cfg.publishes_per_tf:
            self._tf_pub = self.create_publisher(TFMessage, '/tf', QoSProfile(depth=100))
            self._static_tf_pub = self.create_publisher(TFMessage, '/tf_static', QoSProfile(
                depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL))
            self._static_tf_pub.publish(conversions.static_tf_message(
                0, self._plant.frame_poses(), dvl_mount(self._navigation_params)))
        # The URDF the plant was built from, latched as robot_state_publisher offers it, so
        # that RViz, Foxglove and a recording draw the robot.
        self._description_pub = self.create_publisher(String, '/robot_description', QoSProfile(
            depth=1, reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.TRANSIENT_LOCAL))
        self._description_pub.publish(String(data=self._plant.model.description.urdf_text))
        # The hot topics go as raw CDR through fixed layouts (uvms_common.cdr_codecs).
        if self._plant_side is None:
            self.create_subscription(ActuatorCommand, 'command/actuators', self._on_command,
                                     input_qos(cfg.mode == 'lockstep'), raw=True)
        self._commands = raw_conversions.ActuatorCommandReader(self._plant.n_thrusters,
                                                               self._plant.joint_names)
        # imu, dvl, depth (position_fix) only when asked for: recordings stay as they were.
        devices = cfg.devices
        navigation_args = (self, self._navigation_params, params.sensor.seed, devices)
        self._navigation = (None if not self._navigation_params.switch.enabled
                            else NavigationTopics(*navigation_args) if self._plant_side is None
                            else PlantSideNavigation(self._plant_side, *navigation_args))
        # Device timing (uvms_sim.device_delivery): an ideal run takes exactly today's path.
        self._devices = DeviceDelivery(devices, params.sensor.seed, self._plant.n_joints)
        self._messages = raw_conversions.RawStateMessages(self._plant.joint_names)
        self._parents = conversions.frame_parents(self._plant.model.frame_names)

        self._command: tuple[int, Any, Any] | None = None
        self._stale = False
        self._published = 0
        self._awaiting_since: Any = None
        self._finished = False
        self.timeouts = 0
        self._realtime_start: Any = None
        # Real time: ticks that end behind the wall clock, counted after the start-up grace
        # (the first ticks wait for the other nodes and the kernels, which is no fault).
        self._behind = MissCounter(round(cfg.wall_period_s * 1e9))
        # Until the loop is closed (docs/running.md, start-up): None once it is, or unwatched.
        self._startup: StartupWatch | None = None
        self._held_published_ns = 0
        # Before the first state and physics: the recorder and the mission, when asked.
        self._gates = StartGates(self, cfg.startup, recorded_publishers(
            self.get_namespace(), [self._clock_pub, self._joint_pub, self._odom_pub,
                                   self._wrench_pub, self._ee_pub, self._contact_pub]),
            realtime_hold=cfg.mode != 'lockstep' and cfg.startup.hold)
        if cfg.mode == 'lockstep':
            self._kick = self.create_timer(1e-3, self._on_kick)
            period = min(max(cfg.lockstep_timeout_s / 4.0, 1e-3), 0.25)
            self._wait = AttentiveWait(round(period * 1e9))
            self.create_timer(period, self._on_lockstep_timer)
        else:
            self.create_timer(cfg.wall_period_s, self._on_realtime_tick)
        self._diagnostics = DiagnosticsPublisher(
            self, robot_name(self._plant.model.description.urdf_text))
        self._diagnostics.add('simulation', self._report)
        self._meters = (RateMeter(), RateMeter(), RateMeter())  # steps, sim seconds, timeouts
        self.get_logger().info(
            f'{cfg.mode} simulation of robot {self.robot_name} at '
            f'{1e9 / cfg.physics_dt_ns:g} Hz, state published every '
            f'{cfg.steps_per_publish} steps, wall {"on" if cfg.wall_enabled else "off"}'
            + (f', {cfg.real_time_factor:g}x real time'
               if cfg.mode != 'lockstep' and cfg.real_time_factor != 1.0 else '')
            + f', {devices.summary()}')

    @property
    def joint_names(self) -> tuple[str, ...]:
        """The plant's joints, in the order of its coordinates and its torque inputs."""
        return tuple(self._plant.joint_names)

    @property
    def sim_time_ns(self) -> int:
        """Simulated time of the plant (ns)."""
        return self._plant.t_ns

    @property
    def finished(self) -> bool:
        """True once ``duration_s`` is reached and the last state has been answered."""
        return self._finished

    def _on_command(self, data: bytes) -> None:
        """Keep a valid command; in lockstep only the one for the current state, then step."""
        try:
            command = self._commands.read(data)
        except MalformedPayloadError as exc:
            self.get_logger().error(f'malformed actuator command payloads (counted on '
                                    f'/diagnostics), first: {exc}', once=True)
            return
        except CommandError as exc:
            self.get_logger().error(f'rejected actuator command: {exc}',
                                    throttle_duration_sec=1.0)
            return
        if self._settings.mode != 'lockstep':
            self._take(command)
            return
        if self._awaiting_since is None or command[0] != self._plant.t_ns:
            # Not the answer the exchange waits for (an old or foreign stamp): kept out of
            # the state, so that no other publisher can stall or steer the lockstep run.
            self.get_logger().debug(
                f'ignored actuator command stamped {command[0] * 1e-9:.6f} s, awaiting '
                f'{self._plant.t_ns * 1e-9:.6f} s')
            return
        self._command = command
        if self._startup is not None:
            self._startup.core.actuator_command()  # closed; dropped at the next timer turn
        self._answered()

    def _take(self, command: tuple[int, Any, Any]) -> None:
        """Real time: step on this command from now on (and the loop is closed, if held)."""
        self._command = command
        if self._startup is not None:
            self._startup.core.actuator_command()

    def _on_kick(self) -> None:
        """Lockstep start: publish the initial state once the executor runs (and recorder)."""
        if not self._gates.first_state(self.get_clock().now().nanoseconds):
            return  # the kick timer asks again
        self._kick.cancel()
        self._publish_state()
        self._watch_startup()

    def _on_lockstep_timer(self) -> None:
        """Lockstep timeout: re-offer the state before any command, else step on the last."""
        self._startup_closed()
        if self._awaiting_since is None:
            return
        # Counted only while this process ran its timer on time (uvms_sim.lockstep_wait).
        waited_s = self._wait.check(self.get_clock().now().nanoseconds) * 1e-9
        if waited_s < self._settings.lockstep_timeout_s:
            return
        if self._command is None:
            self._check_startup_time()
            self.get_logger().info('waiting for the first actuator command',
                                   throttle_duration_sec=5.0)
            self._publish_state()
            return
        self.timeouts += 1
        self.get_logger().warning(
            f'no actuator command stamped t = {self._plant.t_ns * 1e-9:.3f} s after '
            f'{self._wait.wall_ns * 1e-9:.2f} s: stepping with the last command',
            throttle_duration_sec=5.0)
        self._answered()

    def _on_realtime_tick(self) -> None:
        """Real time: step until simulated time has caught up with the wall clock.

        One step per period when the timer is on time; after a late tick, up to
        ``_MAX_CATCH_UP_STEPS`` at once, so simulated time keeps pace with the wall clock
        instead of silently dropping steps. Beyond that the simulation falls behind (warned).
        Simulated time due is the wall time since the loop closed times ``real_time_factor``.
        """
        if self._finished:
            return
        now = self.get_clock().now()
        if self._realtime_start is None and not self._loop_closed(now.nanoseconds):
            return
        if self._realtime_start is None:
            self._realtime_start = now
        due_ns = round((now - self._realtime_start).nanoseconds
                       * self._settings.real_time_factor)
        publish_every_ns = self._plant.dt_ns * self._settings.steps_per_publish
        for _ in range(_MAX_CATCH_UP_STEPS):
            if self._plant.t_ns > due_ns:
                break  # caught up: a period on time, counted as one
            if self._plant.t_ns % publish_every_ns == 0:
                self._publish_state()
                if self._finished:
                    return
            self._step()
        behind_s = (due_ns - self._plant.t_ns) * 1e-9
        share = self._behind.tick(now.nanoseconds, ran=behind_s <= 0.0, on_time=True)
        if share is not None:
            self.get_logger().warning(
                f'the simulation ended {share:.1%} of its ticks in the last {MISS_WINDOW_S:g} s '
                f'behind real time (now {max(behind_s, 0.0) * 1e3:.1f} ms)')
        elif behind_s > 0.0 and due_ns < STARTUP_GRACE_S * 1e9:
            self.get_logger().info(
                f'the simulation runs {behind_s * 1e3:.1f} ms behind real time (start-up)',
                once=True)

    def _answered(self) -> None:
        """Lockstep: the published state is answered; integrate to the next one, or finish."""
        self._awaiting_since = None
        if self._at_end():
            self._finished = True
            return
        for _ in range(self._settings.steps_per_publish):
            self._step()
        self._publish_state()

    def _at_end(self) -> bool:
        """True once the simulated time reached ``duration_s`` (never when it is 0)."""
        duration_ns = self._settings.duration_ns
        return duration_ns > 0 and self._plant.t_ns >= duration_ns

    def _step(self) -> None:
        """One plant step with the command, or zeros when there is none or it is stale."""
        thrusts = torques = None
        if self._command is not None:
            age_ns = self._plant.t_ns - self._command[0]
            stale = age_ns > self._settings.watchdog_timeout_ns
            if stale and not self._stale:
                self.get_logger().warning(
                    f'actuator command is {age_ns * 1e-9:.3f} s old (limit '
                    f'{self._settings.watchdog_timeout_ns * 1e-9:g} s): thrusters and motors '
                    'set to zero')
            elif self._stale and not stale:
                self.get_logger().info('fresh actuator commands: thrusters and motors resumed')
            self._stale = stale
            if not stale:
                thrusts, torques = self._command[1], self._command[2]
        if thrusts is None:
            thrusts, torques = [0.0] * self._plant.n_thrusters, [0.0] * self._plant.n_joints
        thrusts, torques = self._devices.commands(self._plant.t_ns, thrusts, torques)
        try:
            self._plant.step(thrusts, torques)
        except SimulationError as exc:
            self.get_logger().fatal(f'simulation stopped: {exc}')
            raise

    def _report(self) -> Report:
        """/diagnostics: step rate and real-time factor on the wall clock, lockstep timeouts.

        ``steps`` and ``states_published`` are exact counts (simulated time in steps, the
        states published so far): a reader gets the share of simulated-time slots the
        simulator filled without counting messages, which DDS may drop on the way.
        """
        now_ns = self.get_clock().now().nanoseconds  # the system clock: no use_sim_time here
        t_ns = self._plant.t_ns
        steps, seconds, timeouts = self._meters
        step_hz = steps.rate_hz(t_ns // self._plant.dt_ns, now_ns)
        factor = seconds.rate_hz(t_ns * 1e-9, now_ns)
        new_timeouts = timeouts.rate_hz(self.timeouts, now_ns)
        values = {'mode': self._settings.mode, 'sim_time_s': t_ns * 1e-9, 'step_rate_hz': step_hz,
                  'real_time_factor': factor, 'lockstep_timeouts': self.timeouts,
                  'steps': t_ns // self._plant.dt_ns, 'states_published': self._published,
                  'steps_behind_real_time': self._behind.missed,
                  'malformed_commands': self._commands.decoder.malformed,
                  'behind_real_time_share': self._behind.share}
        return simulator_report(
            values, finished=self._finished,
            holding_for=(self._startup.core.waiting_for() if self._startup is not None
                         else None),
            first_command=self._command is not None, new_timeouts=new_timeouts,
            asked_factor=self._settings.real_time_factor)

    def _publish_state(self) -> None:
        """Publish /clock, the sensor topics and, when due, ee_pose, contact and /tf (at t_k)."""
        tf_due = (self._tf_pub is not None
                  and self._published % self._settings.publishes_per_tf == 0)
        ground_truth_due = self._published % self._settings.publishes_per_ground_truth == 0
        seen = self._plant.observe(all_frames=tf_due)
        out = self._messages
        delivered = self._devices.observation(seen)
        out.update(delivered, ground_truth=ground_truth_due)
        if self._plant_side is not None:
            self._plant_side.observe(delivered)
        if self._navigation is not None:  # before /clock, on which the estimator publishes
            self._navigation.publish(seen.t_ns, seen.q, seen.w)
        self._clock_pub.publish(out.clock)
        devices_here = self._plant_side is None
        if devices_here and self._published % self._settings.publishes_per_joint_state == 0:
            self._joint_pub.publish(out.joint_state)
        self._odom_pub.publish(out.odometry)
        if devices_here:
            self._wrench_pub.publish(out.wrench)
        if ground_truth_due:
            self._ee_pub.publish(out.ee_pose)
            self._contact_pub.publish(out.contact)
            self._ocean.publish(seen.t_ns)
        if tf_due:
            self._tf_pub.publish(conversions.tf_message(seen.t_ns, seen.poses, self._parents))
        self._published += 1
        if self._plant_side is not None:
            command = self._plant_side.command(seen.t_ns)
            if command is not None:
                self._take((seen.t_ns, *command))
        if self._settings.mode == 'lockstep':
            self._awaiting_since = self.get_clock().now()
            self._wait.start(self._awaiting_since.nanoseconds)
        elif self._at_end():
            self._finished = True


def main(args: list[str] | None = None) -> None:
    """Run the simulator node until SIGINT/SIGTERM or the end of its duration."""
    sys.exit(run_node(SimulatorNode, args, 'simulator', (SimParameterError, ParameterException),
                      finished=lambda node: node.finished))

if __name__ == '__main__':
    main()
