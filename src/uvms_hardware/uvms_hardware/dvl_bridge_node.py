"""The ``dvl_bridge`` node: a Water Linked DVL A50/A125 (TCP JSON) as the ``dvl`` topic.

A managed node on the bridges' base (``uvms_hardware.bridge_node``, ``autostart``): configure
connects to ``address`` (``HOST[:PORT]``, port 16171 by default) and waits
``connect_timeout_s`` for it; activate publishes. Each valid
(bottom-locked) velocity report becomes ``dvl`` (geometry_msgs/TwistWithCovarianceStamped in
``dvl_link``, as the simulator publishes it and ArduSub's DVL extension drops invalid ones):
the velocity turned from the DVL's own frame (``hardware.yaml``: ``dvl.mounting_rpy_rad``)
into dvl_link (``navigation.yaml``: ``navigation.dvl.orientation_rpy``), its covariance the
report's (else fom^2). Stamped with the report's own ``time_of_validity`` (the centre of
the ping, µs on the DVL's clock) mapped into the node clock through the DVL clock's offset,
estimated from each report's ``time_of_transmission`` against its arrival
(`uvms_hardware.device_time`: the minimum-delay envelope, so a late arrival does not move
it); a report without a time of validity, or while the two clocks visibly run at different
rates (WARN), is stamped at its arrival and counted. A report is published once, when it
arrives: a silent DVL publishes nothing. The connection is retried
every ``reconnect_period_s``. /diagnostics: lost lock (WARN), a silent or disconnected DVL
(ERROR), malformed lines counted, the clock offset, skew, spread and arrival jitter.
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
from uvms_hardware.device_time import DeviceClockEstimator
from uvms_hardware.dvl_link import DvlLink
from uvms_hardware.dvl_protocol import VelocityReport, report_in_link, rot_link_from_dvl
from uvms_hardware.errors import HardwareError
from uvms_hardware.hardware_config import Spec, hardware_section
from uvms_hardware.stop_report import write_stop_report

DEFAULT_PORT = 16171
#: How often the link's queue is drained (s).
DRAIN_PERIOD_S = 0.01
_US = 1e-6

SPECS = (
    Spec('address', LOOPBACK, 'The DVL: HOST[:PORT] (TCP; port 16171 when not given)'),
    Spec('connect_timeout_s', 10.0, 'Wait for the connection at configure (s): the DVL may '
         'come up after the bridge (launch order)', 0.1, 120.0),
    Spec('reconnect_period_s', 1.0, 'Between connection attempts (s)', 0.05, 60.0),
    Spec('timeout_s', 1.0, 'No report this long: the DVL is silent, ERROR (s)', 0.1, 30.0),
    Spec('mounting_rpy_rad', [0.0, 0.0, 0.0], "The DVL's own frame in base_link_frd (rad)"),
    Spec('clock_window_s', 30.0, "Reports the DVL clock's offset is estimated over (s)",
         2.0, 600.0),
    Spec('clock_reset_s', 0.2, "The DVL clock's offset jumps by more than this: estimated "
         'again from the next report (s; an NTP step on the DVL)', 0.01, 10.0),
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
        self.clock: DeviceClockEstimator | None = None
        self.published = 0
        self.stamped_at_arrival = 0
        self.start()

    def configure_device(self) -> None:
        """Connect to the DVL (refused when it does not answer), make the publisher."""
        v = self.values
        address = parse_host_port(str(v['address']), self.default_port, 'address')
        window_s = float(v['clock_window_s'])
        self.clock = DeviceClockEstimator(window_s, window_s / 30.0, float(v['clock_reset_s']))
        self.link = link = DvlLink(address, float(v['reconnect_period_s']),
                                   arrival_clock=self._local_s).start()
        if not link.wait_connected(float(v['connect_timeout_s'])):
            raise DvlBridgeError(f'no DVL at {address.host}:{address.port} ({link.last_error})')
        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        self._dvl = self.own(self.destroy_publisher,
                             self.create_publisher(TwistWithCovarianceStamped, 'dvl', qos))
        self.device_timer(DRAIN_PERIOD_S, self._drain)
        self.get_logger().info(f'DVL at {address.host}:{address.port}; publishing dvl')

    def put_device_back(self) -> list[str]:
        """Nothing to put back (the DVL is only listened to); said, for the launcher."""
        done = 'nothing to put back: the DVL was only listened to'
        self.get_logger().info(f'put back: {done}')
        write_stop_report(self.get_name(), done, [])
        return []

    def release_device(self) -> None:
        """Disconnect (a sensor: nothing on the device to put back)."""
        if self.link is not None:
            self.link.stop()
        self.link, self.clock = None, None

    def _local_s(self) -> float:
        """The node clock (s): what stamps are in (``/clock`` beside the simulator)."""
        return self.get_clock().now().nanoseconds * 1e-9

    def stamp_s(self, report: VelocityReport, arrival_s: float) -> float:
        """When the report's velocity was measured, on the node clock (s)."""
        clock = self.clock
        sent_us = report.time_of_transmission_us or report.time_of_validity_us
        if clock is None or sent_us is None or report.time_of_validity_us is None:
            self.stamped_at_arrival += 1
            return arrival_s
        clock.add(sent_us * _US, arrival_s)
        if not clock.rates_agree:
            self.stamped_at_arrival += 1
            return arrival_s
        return clock.to_local(report.time_of_validity_us * _US) or arrival_s

    def _drain(self) -> None:
        link = self.link
        if link is None:
            return
        for arrival_s, report in link.take():
            stamp_s = self.stamp_s(report, arrival_s)  # every report times the clock
            if not (self.device_active and report.valid):
                continue
            v, cov = report_in_link(report, self.rot)
            self._dvl.publish(bm.dvl_message(round(stamp_s * 1e9), v.tolist(),
                                             cov.ravel().tolist()))
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
                  'connects': link.connects, 'last_error': link.last_error or p.last_error,
                  'stamped_at_arrival': self.stamped_at_arrival,
                  **(self.clock.report() if self.clock is not None else {})}
        if not link.connected:
            return Report(ERROR, f'DVL disconnected: {link.last_error}', values)
        if age_s > float(self.values['timeout_s']):
            return Report(ERROR, f'DVL silent for {age_s:.1f} s', values)
        if link.last_valid is False:
            return Report(WARN, 'no bottom lock: velocity not published', values)
        if self.clock is not None and not self.clock.rates_agree:
            return Report(WARN, "the DVL's clock does not run at the node clock's rate (beside "
                          "a simulator, the twin must run on the plant's time): stamped at "
                          'arrival', values)
        return Report(OK, 'bottom lock', values)


def main(args: list[str] | None = None) -> None:
    """Run the dvl_bridge node until SIGINT/SIGTERM."""
    run_bridge(DvlBridgeNode, args, 'dvl_bridge')


if __name__ == '__main__':
    main()
