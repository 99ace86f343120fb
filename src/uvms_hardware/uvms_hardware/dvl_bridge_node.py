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

The device is `uvms_hardware.dvl_component.DvlComponent` (no ROS); this node only turns its
lifecycle hooks into the component's, its drain timer into ``read`` and its state and report
into messages.
"""

from __future__ import annotations

from typing import Any

from geometry_msgs.msg import TwistWithCovarianceStamped
from uvms_common.clock_read import now_ns
from uvms_common.diagnostics import ERROR, OK, WARN, Report
from uvms_common.node_construction import destroyed_if_construction_fails
from uvms_common.parameter_declaration import declare_specs

from uvms_description.robots import RobotParameter, robot_parameters
from uvms_hardware import bridge_messages as bm
from uvms_hardware.bridge_node import DEVICE_TOPIC_QOS, BridgeNode, run_bridge
from uvms_hardware.component import logger_log
from uvms_hardware.dvl_component import DEFAULT_PORT, SPECS, DvlBridgeError, DvlComponent
from uvms_hardware.dvl_link import DvlLink
from uvms_hardware.dvl_protocol import rot_link_from_dvl
from uvms_hardware.errors import HardwareError
from uvms_hardware.hardware_config import hardware_section

__all__ = ['DEFAULT_PORT', 'DRAIN_PERIOD_S', 'SPECS', 'DvlBridgeError', 'DvlBridgeNode', 'main']

LEVELS = (OK, WARN, ERROR)
#: How often the link's queue is drained (s).
DRAIN_PERIOD_S = 0.01


class DvlBridgeNode(BridgeNode):
    """Water Linked DVL reports (a `DvlComponent`) -> ``dvl``."""

    error_type = DvlBridgeError
    diagnostics_task = 'dvl'

    @destroyed_if_construction_fails
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
        values = declare_specs(self, SPECS, robot, lambda spec, exc: DvlBridgeError(
            f'invalid parameter {spec.name!r}: {exc}'))
        rot = rot_link_from_dvl([float(a) for a in values['mounting_rpy_rad']],
                                [float(a) for a in link_rpy])
        mounted_m = [float(x) for x in section.get('mounting_position_m', link_position_m)]
        if mounted_m != link_position_m:
            # The estimator's lever arm is navigation.yaml's: a DVL elsewhere biases it.
            self.get_logger().warning(
                f'hardware.yaml dvl.mounting_position_m {mounted_m} differs from navigation.yaml '
                f'navigation.dvl.position_m {link_position_m}, the lever arm the estimator uses')
        self.component = DvlComponent(
            values, rot, int(section.get('port', DEFAULT_PORT)), self.get_name(),
            clock=self.now_s, local_clock=lambda: now_ns(self.get_clock()) * 1e-9,
            log=logger_log(self.get_logger()))
        self.start()

    @property
    def values(self) -> dict[str, Any]:
        """The settings (parameters) of the component."""
        return self.component.values

    @property
    def link(self) -> DvlLink | None:
        """The component's TCP link (None while unconfigured)."""
        return self.component.link

    @property
    def published(self) -> int:
        """Messages published on dvl (one per valid report while active)."""
        return self.component.published

    def configure_device(self) -> None:
        """Connect (refused when no DVL answers), make the publisher and the drain timer."""
        self.component.configure()
        self._dvl = self.own(self.destroy_publisher, self.create_publisher(
            TwistWithCovarianceStamped, 'dvl', DEVICE_TOPIC_QOS))
        self.device_timer(DRAIN_PERIOD_S, self._drain)
        address = self.component.address
        assert address is not None
        self.get_logger().info(f'DVL at {address.host}:{address.port}; publishing dvl')

    def activate_device(self) -> None:
        """Publish from now on (nothing on the DVL changes)."""
        self.component.activate()

    def put_device_back(self) -> list[str]:
        """Nothing to put back (the DVL is only listened to); said, for the launcher."""
        return self.component.put_back()

    def release_device(self) -> None:
        """Disconnect."""
        self.component.release()

    def _drain(self) -> None:
        self.component.read(self.now_s())
        for m in self.component.state().measurements:
            self._dvl.publish(bm.dvl_message(round(m.stamp_s * 1e9), m.v_m_s.tolist(),
                                             m.covariance.ravel().tolist()))

    def device_report(self) -> Report:
        """The component's report."""
        report = self.component.report(self.now_s())
        return Report(LEVELS[report.level], report.message, dict(report.values))


def main(args: list[str] | None = None) -> None:
    """Run the dvl_bridge node until SIGINT/SIGTERM."""
    run_bridge(DvlBridgeNode, args, 'dvl_bridge')


if __name__ == '__main__':
    main()
