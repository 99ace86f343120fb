"""The ``dvl_bridge`` node: a Water Linked DVL A50/A125 (TCP JSON) as the ``dvl`` topic.

A managed node (``autostart``): configure connects to ``address`` (``HOST[:PORT]``, port
16171 by default) and waits ``connect_timeout_s`` for it; activate publishes. Each valid
(bottom-locked) velocity report becomes ``dvl`` (geometry_msgs/TwistWithCovarianceStamped in
``dvl_link``, as the simulator publishes it and ArduSub's DVL extension drops invalid ones):
the velocity turned from the DVL's own frame (``hardware.yaml``: ``dvl.mounting_rpy_rad``)
into dvl_link (``navigation.yaml``: ``navigation.dvl.orientation_rpy``), its covariance the
report's (else fom^2). Stamped with the node clock at arrival. The connection is retried
every ``reconnect_period_s``. /diagnostics: lost lock (WARN), a silent or disconnected DVL
(ERROR), malformed lines counted.
"""

from __future__ import annotations

import sys
from typing import Any

from geometry_msgs.msg import TwistWithCovarianceStamped
from rclpy.exceptions import ParameterException
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rclpy.qos import QoSProfile, ReliabilityPolicy
from uvms_common.diagnostics import ERROR, OK, WARN, DiagnosticsPublisher, Report
from uvms_common.lifecycle import autostart, declare_autostart, guard_change_state, state_label
from uvms_common.node_main import run_node
from uvms_common.parameter_declaration import declare_specs
from uvms_common.robot_parameters import declare_robot_name

from uvms_description.robots import RobotParameter, robot_parameters
from uvms_hardware import bridge_messages as bm
from uvms_hardware.address import LOOPBACK, parse_host_port
from uvms_hardware.device_clock import DeviceClock
from uvms_hardware.dvl_link import DvlLink
from uvms_hardware.dvl_protocol import report_in_link, rot_link_from_dvl
from uvms_hardware.errors import AddressError, DeviceCheckError, HardwareError
from uvms_hardware.hardware_config import Spec, hardware_section

SUCCESS, FAILURE = TransitionCallbackReturn.SUCCESS, TransitionCallbackReturn.FAILURE
DEFAULT_PORT = 16171

SPECS = (
    Spec('address', LOOPBACK, 'The DVL: HOST[:PORT] (TCP; port 16171 when not given)'),
    Spec('connect_timeout_s', 10.0, 'Wait for the connection at configure (s): the DVL may '
         'come up after the bridge (launch order)', 0.1, 120.0),
    Spec('reconnect_period_s', 1.0, 'Between connection attempts (s)', 0.05, 60.0),
    Spec('timeout_s', 1.0, 'No report this long: the DVL is silent, ERROR (s)', 0.1, 30.0),
    Spec('mounting_rpy_rad', [0.0, 0.0, 0.0], "The DVL's own frame in base_link_frd (rad)"),
)


class DvlBridgeError(HardwareError, ValueError):
    """A parameter of the DVL bridge is invalid."""


class DvlBridgeNode(LifecycleNode):
    """Water Linked DVL reports -> ``dvl``."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__('dvl_bridge', **kwargs)
        self._device_clock = DeviceClock(self)
        self.robot_name = declare_robot_name(self)
        try:
            source, section = hardware_section(self.robot_name, 'dvl')
            navigation = robot_parameters(self.robot_name, 'estimator')
            link_rpy = navigation['navigation.dvl.orientation_rpy'].value
            link_position_m = [float(x) for x in navigation['navigation.dvl.position_m'].value]
        except (HardwareError, ValueError, KeyError) as exc:
            raise DvlBridgeError(f'robot {self.robot_name!r}: {exc}') from exc
        robot = {name: RobotParameter(section[key], source) for name, key in (
            ('mounting_rpy_rad', 'mounting_rpy_rad'), ('timeout_s', 'timeout_s'))
            if key in section}
        self.default_port = int(section.get('port', DEFAULT_PORT))
        self.values = declare_specs(self, SPECS, robot, lambda spec, exc: DvlBridgeError(
            f'invalid parameter {spec.name!r}: {exc}'))
        self.rot = rot_link_from_dvl([float(a) for a in self.values['mounting_rpy_rad']],
                                     [float(a) for a in link_rpy])
        mounted_m = [float(x) for x in section.get('mounting_position_m', link_position_m)]
        if mounted_m != link_position_m:
            # The estimator's lever arm is navigation.yaml's: a DVL elsewhere biases it.
            self.get_logger().warning(
                f'hardware.yaml dvl.mounting_position_m {mounted_m} differs from navigation.yaml '
                f'navigation.dvl.position_m {link_position_m}, the lever arm the estimator uses')
        starting = declare_autostart(self)
        guard_change_state(self)
        self.link: DvlLink | None = None
        self.published = 0
        self._active = False
        self._entities: list[Any] = []
        self._diagnostics = DiagnosticsPublisher(self, self.robot_name)
        self._diagnostics.add('dvl', self._report)
        if starting and not autostart(self):
            self.destroy_node()
            raise DeviceCheckError('dvl_bridge: cannot configure and activate (logged)')

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Connect to the DVL, make the publisher."""
        v = self.values
        try:
            address = parse_host_port(str(v['address']), self.default_port, 'address')
        except AddressError as exc:
            self.get_logger().error(f'configure failed: {exc}')
            return FAILURE
        self.link = DvlLink(address, float(v['reconnect_period_s'])).start()
        if not self.link.wait_connected(float(v['connect_timeout_s'])):
            self.get_logger().error(f'configure failed: no DVL at {address.host}:'
                                    f'{address.port} ({self.link.last_error})')
            self._stop_link()
            return FAILURE
        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        self._dvl = self.create_publisher(TwistWithCovarianceStamped, 'dvl', qos)
        self._entities = [(self.destroy_publisher, self._dvl),
                          (self.destroy_timer, self._device_clock.timer(0.01, self._drain))]
        self.get_logger().info(f'DVL at {address.host}:{address.port}; publishing dvl')
        return SUCCESS

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Publish from now on."""
        self._active = True
        return super().on_activate(state)

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Stop publishing (a sensor: nothing on the device to put back)."""
        self._active = False
        return super().on_deactivate(state)

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        """Disconnect, drop the publisher."""
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
        self._stop_link()

    def _stop_link(self) -> None:
        if self.link is not None:
            self.link.stop()
        self.link = None

    def _drain(self) -> None:
        if self.link is None:
            return
        for _, report in self.link.take():
            if not (self._active and report.valid):
                continue
            v, cov = report_in_link(report, self.rot)
            t_ns = self.get_clock().now().nanoseconds
            self._dvl.publish(bm.dvl_message(t_ns, v.tolist(), cov.ravel().tolist()))
            self.published += 1

    def _report(self) -> Report:
        state, link = state_label(self), self.link
        if link is None:
            return Report(WARN, f'{state}: not connected', {'lifecycle_state': state})
        age_s = link.clock() - link.last_report_s
        p = link.parser
        values = {'lifecycle_state': state, 'connected': link.connected,
                  'report_age_s': age_s, 'bottom_lock': link.last_valid,
                  'reports': p.reports, 'published': self.published,
                  'malformed_lines': p.malformed, 'ignored_reports': p.ignored,
                  'connects': link.connects, 'last_error': link.last_error or p.last_error}
        if not link.connected:
            return Report(ERROR, f'DVL disconnected: {link.last_error}', values)
        if age_s > float(self.values['timeout_s']):
            return Report(ERROR, f'DVL silent for {age_s:.1f} s', values)
        if link.last_valid is False:
            return Report(WARN, 'no bottom lock: velocity not published', values)
        return Report(OK, 'bottom lock', values)


def main(args: list[str] | None = None) -> None:
    """Run the dvl_bridge node until SIGINT/SIGTERM."""
    sys.exit(run_node(DvlBridgeNode, args, 'dvl_bridge',
                      (DvlBridgeError, DeviceCheckError, ParameterException)))


if __name__ == '__main__':
    main()
