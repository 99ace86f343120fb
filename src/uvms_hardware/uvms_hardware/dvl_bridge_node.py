"""The ``dvl_bridge`` node: a Water Linked DVL A50/A125 (TCP JSON) as the ``dvl`` topic.

A managed node on the bridges' base (``uvms_hardware.bridge_node``, ``autostart``): configure
connects to ``address`` (``HOST[:PORT]``, port
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

from typing import Any

from geometry_msgs.msg import TwistWithCovarianceStamped
from rclpy.qos import QoSProfile, ReliabilityPolicy
from uvms_common.diagnostics import ERROR, OK, WARN, Report
from uvms_common.parameter_declaration import declare_specs

from uvms_description.robots import RobotParameter, robot_parameters
from uvms_hardware import bridge_messages as bm
from uvms_hardware.address import LOOPBACK, parse_host_port
from uvms_hardware.bridge_node import BridgeNode, run_bridge
from uvms_hardware.dvl_link import DvlLink
from uvms_hardware.dvl_protocol import report_in_link, rot_link_from_dvl
from uvms_hardware.errors import HardwareError
from uvms_hardware.hardware_config import Spec, hardware_section

DEFAULT_PORT = 16171
#: How often the link's queue is drained (s).
DRAIN_PERIOD_S = 0.01

SPECS = (
    Spec('address', LOOPBACK, 'The DVL: HOST[:PORT] (TCP; port 16171 when not given)'),
    Spec('connect_timeout_s', 10.0, 'Wait for the connection at configure (s): the DVL may '
         'come up after the bridge (launch order)', 0.1, 120.0),
    Spec('reconnect_period_s', 1.0, 'Between connection attempts (s)', 0.05, 60.0),
    Spec('timeout_s', 1.0, 'No report this long: the DVL is silent, ERROR (s)', 0.1, 30.0),
    Spec('mounting_rpy_rad', [0.0, 0.0, 0.0], "The DVL's own frame in base_link_frd (rad)"),
)


class DvlBridgeError(HardwareError, ValueError):
    """A parameter of the DVL bridge is invalid, or no DVL answers at configure."""


class DvlBridgeNode(BridgeNode):
    """Water Linked DVL reports -> ``dvl``."""

    error_type = DvlBridgeError
    diagnostics_task = 'dvl'

    def __init__(self, **kwargs: Any) -> None:
        super().__init__('dvl_bridge', **kwargs)
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
        self.link: DvlLink | None = None
        self.published = 0
        self.start()

    def configure_device(self) -> None:
        """Connect to the DVL (refused when it does not answer), make the publisher."""
        v = self.values
        address = parse_host_port(str(v['address']), self.default_port, 'address')
        self.link = link = DvlLink(address, float(v['reconnect_period_s'])).start()
        if not link.wait_connected(float(v['connect_timeout_s'])):
            raise DvlBridgeError(f'no DVL at {address.host}:{address.port} ({link.last_error})')
        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        self._dvl = self.own(self.destroy_publisher,
                             self.create_publisher(TwistWithCovarianceStamped, 'dvl', qos))
        self.device_timer(DRAIN_PERIOD_S, self._drain)
        self.get_logger().info(f'DVL at {address.host}:{address.port}; publishing dvl')

    def release_device(self) -> None:
        """Disconnect (a sensor: nothing on the device to put back)."""
        if self.link is not None:
            self.link.stop()
        self.link = None

    def _drain(self) -> None:
        link = self.link
        if link is None:
            return
        for _, report in link.take():
            if not (self.device_active and report.valid):
                continue
            v, cov = report_in_link(report, self.rot)
            t_ns = self.get_clock().now().nanoseconds
            self._dvl.publish(bm.dvl_message(t_ns, v.tolist(), cov.ravel().tolist()))
            self.published += 1

    def device_report(self) -> Report:
        """Connection, lock, silence, counters."""
        link = self.link
        if link is None:
            return Report(WARN, 'not connected', {})
        age_s = link.clock() - link.last_report_s
        p = link.parser
        values = {'connected': link.connected,
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
    run_bridge(DvlBridgeNode, args, 'dvl_bridge')


if __name__ == '__main__':
    main()
