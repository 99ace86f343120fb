"""The ``estimator`` node: fuses imu, dvl, depth (and position_fix) into odometry/filtered.

A managed node (``autostart``: it activates itself unless false): configure reads the robot's
navigation figures (``navigation.yaml``, section ``/**/estimator``) and builds the filter and
the subscriptions; activate starts publishing. The filter (``uvms_navigation.eskf``) advances
on each IMU sample and fuses the others as they arrive; on every ``/clock`` tick the node
publishes ``odometry/filtered`` stamped with it (the estimate carried to that instant), so a
lockstep controller finds an estimate for each state. ``/diagnostics``: DVL lost, covariance
growing, horizontal sigma (``uvms_navigation.health``), malformed input payloads.

Inputs and output travel as raw CDR through the fixed layouts of ``uvms_common.hot_messages``
(``uvms_navigation.raw_conversions``), as every topic of the control period does; a payload
that is no message of its topic's type is counted, logged once and dropped.
"""

from __future__ import annotations

import sys
from typing import Any

import numpy as np
from geometry_msgs.msg import PoseWithCovarianceStamped, TwistWithCovarianceStamped
from nav_msgs.msg import Odometry
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.exceptions import ParameterException
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Imu
from uvms_common.cdr_codecs import MalformedPayloadError
from uvms_common.diagnostics import ERROR, OK, WARN, DiagnosticsPublisher, Report
from uvms_common.lifecycle import autostart, declare_autostart, guard_change_state, state_label
from uvms_common.node_construction import destroyed_if_construction_fails
from uvms_common.node_main import run_node
from uvms_common.raw_clock import take_clock_raw
from uvms_model.errors import ModelError
from uvms_model.nav_sensor_parameters import NAVIGATION_PARAMETER_SPECS, NavigationParameters

from uvms_common import direct_topics
from uvms_common import robot_parameters as robots
from uvms_navigation import raw_conversions
from uvms_navigation.eskf import ErrorStateEkf, EstimatorSettings
from uvms_navigation.health import HealthLimits, HealthMonitor

SUCCESS, FAILURE = TransitionCallbackReturn.SUCCESS, TransitionCallbackReturn.FAILURE
_LEVELS = {0: OK, 1: WARN, 2: ERROR}

#: The estimator's own parameters: name, default, description with unit.
ESTIMATOR_PARAMETERS: tuple[tuple[str, Any, str], ...] = (
    ('estimator.initial_position_m', [0.0, 0.0, 0.0],
     'Start position guess in map_ned (m); z is replaced by the first depth reading.'),
    ('estimator.initial_position_sigma_m', 1.0, 'Start std of the position (m).'),
    ('estimator.initial_velocity_sigma_m_s', 0.1, 'Start std of the velocity (m/s).'),
    ('estimator.dvl_gate', 16.27, 'Chi-square gate of a DVL innovation (3 dof, 0.999).'),
    ('estimator.dvl_timeout_s', 2.0, 'Time without a DVL velocity after which it is lost (s).'),
    ('estimator.position_sigma_warn_m', 0.5, 'Horizontal position std that warns (m).'),
    ('estimator.position_sigma_error_m', 2.0, 'Horizontal position std that is an error (m).'),
)


class EstimatorError(ValueError):
    """A parameter of the estimator is invalid."""


class EstimatorNode(LifecycleNode):
    """Navigation filter: sensor topics in, odometry/filtered and its health out."""

    @destroyed_if_construction_fails
    def __init__(self, **kwargs: Any) -> None:
        super().__init__('estimator', **kwargs)
        self._clock_source = take_clock_raw(self)  # /clock raw under use_sim_time
        self.robot_name, robot = robots.declare_robot(self)
        names = [s for s in NAVIGATION_PARAMETER_SPECS
                 if not s.name.startswith(('world.', 'navigation.enabled'))]
        self._sensor_values = {s.name: self._declare(s.name, robots.robot_default(
            robot, s.name, s.default), s.description) for s in names}
        self._values = {name: self._declare(name, default, text)
                        for name, default, text in ESTIMATOR_PARAMETERS}
        # The robot's other files give every node their /** values (thrusters, sensor).
        robots.check_all_declared(self, robot, [k for k in robot
                                                if not k.startswith('navigation.')])
        starting = declare_autostart(self)
        guard_change_state(self)
        self.ekf: ErrorStateEkf | None = None
        self._health = HealthMonitor()
        self._entities: list[Any] = []
        self._active = False
        self._error: Exception | None = None
        self._depth: float | None = None
        self._first_attitude: tuple[int, np.ndarray] | None = None
        self._started = False
        self._early_clock_ns: int | None = None
        self._readers = {'imu': raw_conversions.imu_reader(),
                         'dvl': raw_conversions.dvl_reader(),
                         'depth': raw_conversions.depth_reader(),
                         'position_fix': raw_conversions.position_fix_reader(),
                         '/clock': raw_conversions.clock_reader()}
        self._odometry = raw_conversions.OdometryWriter()
        self._diagnostics = DiagnosticsPublisher(self, self.robot_name)
        self._diagnostics.add('estimate', self._report)
        if starting and not autostart(self):
            error = self._error or EstimatorError('the estimator cannot configure and activate')
            self.destroy_node()
            raise error

    def _declare(self, name: str, default: Any, description: str) -> Any:
        descriptor = ParameterDescriptor(description=description, read_only=True)
        try:
            value = self.declare_parameter(name, default, descriptor).value
        except ParameterException as exc:
            raise EstimatorError(f'invalid parameter {name!r}: {exc}') from exc
        return list(value) if isinstance(value, (list, tuple)) or hasattr(value, 'tolist') \
            else value

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Check the parameters, build the filter and subscribe to the sensor topics."""
        try:
            sensors = NavigationParameters.from_flat_dict(self._sensor_values)
            v = self._values
            if len(v['estimator.initial_position_m']) != 3:
                raise EstimatorError('estimator.initial_position_m must have 3 values')
            self.ekf = ErrorStateEkf(EstimatorSettings(
                sensors, float(v['estimator.initial_position_sigma_m']),
                float(v['estimator.initial_velocity_sigma_m_s']), dvl_gate=float(
                    v['estimator.dvl_gate'])))
            self._health = HealthMonitor(HealthLimits(
                float(v['estimator.dvl_timeout_s']), float(v['estimator.position_sigma_warn_m']),
                float(v['estimator.position_sigma_error_m'])))
        except (ModelError, EstimatorError, TypeError) as error:
            self._error = error
            self.get_logger().error(f'configure failed: {error}')
            return FAILURE
        qos = QoSProfile(depth=50, reliability=ReliabilityPolicy.RELIABLE)
        self._odom_pub = self.create_publisher(Odometry, 'odometry/filtered', qos)
        self._entities = [(self.destroy_publisher, self._odom_pub)] + [
            direct_topics.subscribe(
                self, t, n, lambda data, n=n, cb=cb: self._on_payload(n, cb, data), qos,
                raw=True)
            for t, n, cb in (
                (Imu, 'imu', self._on_imu), (TwistWithCovarianceStamped, 'dvl', self._on_dvl),
                (PoseWithCovarianceStamped, 'depth', self._on_depth),
                (PoseWithCovarianceStamped, 'position_fix', self._on_fix),
                (Clock, '/clock', self._on_clock))]
        self._started = False
        self._depth = self._first_attitude = None
        self.get_logger().info('error-state EKF on imu, dvl, depth, position_fix; publishing '
                               'odometry/filtered')
        return SUCCESS

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Publish from now on."""
        self._active = True
        return super().on_activate(state)

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Stop publishing (the filter keeps running on its inputs)."""
        self._active = False
        return super().on_deactivate(state)

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Drop the filter, its publisher and subscriptions."""
        self._release()
        return super().on_cleanup(state)

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Release everything from any state."""
        self._release()
        return super().on_shutdown(state)

    def destroy_node(self) -> None:
        """Shut down as rclcpp's lifecycle node does, then destroy."""
        if state_label(self) not in ('finalized', 'unknown') and self.context.ok():
            self.trigger_shutdown()
        self._diagnostics.destroy()
        super().destroy_node()

    def _release(self) -> None:
        self._active = False
        for destroy, entity in reversed(self._entities):
            destroy(entity)
        self._entities = []
        self.ekf = None

    @property
    def malformed(self) -> int:
        """Input payloads that were no message of their topic's type, all topics."""
        return sum(reader.decoder.malformed for reader in self._readers.values())

    def _on_payload(self, topic: str, callback: Any, data: bytes) -> None:
        try:
            t_ns, value = self._readers[topic].read(data)
        except MalformedPayloadError as error:
            self.get_logger().error(f'malformed input payloads (counted on /diagnostics), '
                                    f'first on {topic}: {error}', once=True)
            return
        callback(t_ns, *value)

    def _on_imu(self, t_ns: int, w_m: np.ndarray, f_m: np.ndarray, rpy: np.ndarray) -> None:
        if self.ekf is None:
            return
        if not (np.isfinite(w_m).all() and np.isfinite(f_m).all() and np.isfinite(rpy).all()):
            self.get_logger().error('imu: non-finite reading rejected', throttle_duration_sec=1.0)
            return
        if not self._started:
            self._first_attitude = (t_ns, rpy)
            self._start()
            return
        self.ekf.predict(t_ns, w_m, f_m)
        self.ekf.update_attitude(rpy)

    def _on_dvl(self, t_ns: int, v: np.ndarray) -> None:
        if self.ekf is not None and self._started and np.isfinite(v).all():
            self.ekf.update_dvl(v)

    def _on_depth(self, t_ns: int, depth: float) -> None:
        if self.ekf is None or not np.isfinite(depth):
            return
        if not self._started:
            self._depth = depth
            self._start()
            return
        self.ekf.update_depth(depth)

    def _start(self) -> None:
        """Start the filter once it has an attitude (imu) and a depth, never before.

        A filter started without its depth would publish the start guess's z as the estimate
        and jump by the depth reading's offset a few periods later; a controller holding the
        first estimate then drives the vehicle (and the arm, through the whole-body task) at
        that jump the moment physics runs.
        """
        if self.ekf is None or self._first_attitude is None or self._depth is None:
            return
        t_ns, rpy = self._first_attitude
        p0 = np.array(self._values['estimator.initial_position_m'], dtype=float)
        p0[2] = self._depth
        self.ekf.reset_from_ahrs(t_ns, p0, rpy)
        self._started = True
        if self._early_clock_ns is not None:  # its /clock came first: answer it now
            self._publish(self._early_clock_ns)

    def _on_fix(self, t_ns: int, p: np.ndarray, sigma: np.ndarray) -> None:
        if self.ekf is not None and self._started and np.isfinite(p).all():
            self.ekf.update_position(p, sigma)

    def _on_clock(self, t_ns: int) -> None:
        if not self._started:
            self._early_clock_ns = t_ns
            return
        self._publish(t_ns)

    def _publish(self, t_ns: int) -> None:
        ekf = self.ekf
        if not self._active or ekf is None:
            return
        p, rot, v = ekf.extrapolated(t_ns)
        self._odom_pub.publish(self._odometry.payload(
            t_ns, p, rot, v, ekf.w_body, ekf.pose_covariance(), ekf.twist_covariance()))

    def _report(self) -> Report:
        state = state_label(self)
        malformed = {'malformed_inputs': self.malformed}
        if self.ekf is None or not self._started:
            waiting = ' and '.join(name for name, seen in (
                ('imu', self._first_attitude is not None), ('depth', self._depth is not None))
                if not seen) or 'imu'
            return Report(WARN, f'{state}: waiting for the first {waiting} reading',
                          {'lifecycle_state': state, **malformed})
        level, message, values = self._health.report(self.ekf)
        return Report(_LEVELS[level], message, {'lifecycle_state': state, **values, **malformed})


def main(args: list[str] | None = None) -> None:
    """Run the estimator node until SIGINT/SIGTERM."""
    sys.exit(run_node(EstimatorNode, args, 'estimator', (EstimatorError, ParameterException)))


if __name__ == '__main__':
    main()
