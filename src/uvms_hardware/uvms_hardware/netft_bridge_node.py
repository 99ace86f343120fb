"""The ``netft_bridge`` node: an ATI Net F/T's RDT stream as ``wrench`` in ``ft_sensor_link``.

A managed node (``autostart``). configure finds the calibration, opens the UDP link to
``address`` and checks that the box answers a start request with a record within
``answer_timeout_s`` (then stops it again); activate starts real-time streaming (command 2,
infinite samples); each record becomes a ``geometry_msgs/WrenchStamped`` in ``ft_sensor_link``
(the simulator's wrist-sensor topic and convention, ``uvms_hardware.netft_core``); ``~/bias``
(std_srvs/Trigger) zeroes the present reading (in the bridge: ATI's own bias command is not in
the documents). Watchdog: no record for ``watchdog_timeout_s`` and publishing stops (there is
nothing to publish), /diagnostics turns ERROR, and the start request is sent again once a
second. deactivate, shutdown, SIGINT and SIGTERM send the stop command (command 0).
/diagnostics: records, lost records (from rdt_sequence gaps), bad datagrams, the status word,
the box clock's offset, skew, spread and arrival jitter.

Calibration, never assumed: counts per force and per torque and the RDT output rate come from
the box's own page (``http://HOST:http_port/netftapi2.xml``, the active configuration, as
ATI's demo code reads it; `uvms_hardware.rdt_protocol`), else from the parameters, whose
defaults are the robot's ``hardware.yaml`` ``netft`` section; with neither, configure is
refused naming both. Device time: each record is stamped when the box sampled it, its
rdt_sequence at the RDT rate mapped into the node clock (`uvms_hardware.netft_core`).

The device is `uvms_hardware.netft_component.NetFtComponent` (no ROS); this node only turns
its lifecycle hooks into the component's, its poll timer into ``read`` and its state and
report into messages.
"""

from __future__ import annotations

from typing import Any

from geometry_msgs.msg import WrenchStamped
from rcl_interfaces.msg import ParameterDescriptor
from std_srvs.srv import Trigger
from uvms_common.cdr_codecs import MessageCodec, PayloadWriter
from uvms_common.clock_read import now_ns
from uvms_common.diagnostics import ERROR, OK, WARN, Report
from uvms_common.direct_topics import active_bus
from uvms_common.node_construction import destroyed_if_construction_fails

from uvms_hardware.bridge_messages import stamp
from uvms_hardware.bridge_node import DEVICE_TOPIC_QOS, BridgeNode, run_bridge
from uvms_hardware.component import logger_log
from uvms_hardware.device_clock import stop_requested
from uvms_hardware.hardware_config import HardwareConfigError, NetFtHardware, load_netft
from uvms_hardware.netft_component import (
    BOX_VALUES,
    PARAMETERS,
    RESTART_PERIOD_S,
    NetFtBridgeError,
    NetFtComponent,
    read_calibration,
)
from uvms_hardware.netft_core import NetFtCore

__all__ = ['BOX_VALUES', 'FT_SENSOR_LINK', 'PARAMETERS', 'RESTART_PERIOD_S', 'NetFtBridgeError',
           'NetFtBridgeNode', 'main', 'read_calibration']

LEVELS = (OK, WARN, ERROR)
#: The frame of the wrist sensor's wrench (robot.urdf).
FT_SENSOR_LINK = 'ft_sensor_link'


class NetFtBridgeNode(BridgeNode):
    """ATI Net F/T bridge: the `NetFtComponent`'s records as wrench, its report as diagnostics."""

    error_type = NetFtBridgeError
    diagnostics_task = 'netft'

    @destroyed_if_construction_fails
    def __init__(self, **kwargs: Any) -> None:
        super().__init__('netft_bridge', **kwargs)
        try:
            hardware: NetFtHardware | None = load_netft(self.robot_name)
            problem = ''
        except HardwareConfigError as exc:
            hardware, problem = None, str(exc)
        robot = {name: getattr(hardware, name) for name in BOX_VALUES
                 if hardware is not None and getattr(hardware, name) is not None}
        values = {name: self.declare_parameter(
            name, float(robot.get(name, default)) if name in robot else default,
            ParameterDescriptor(description=text, read_only=True)).value
            for name, default, text in PARAMETERS}
        self.component = NetFtComponent(
            values, hardware, problem, self.get_name(), clock=self.now_s,
            local_clock=lambda: now_ns(self.get_clock()) * 1e-9,
            log=logger_log(self.get_logger()),
            stop_requested=stop_requested)
        #: The wrench's CDR writer in the robot loop (configure), None in a node process.
        self._payload: PayloadWriter | None = None
        self.start()

    @property
    def values(self) -> dict[str, Any]:
        """The settings (parameters) of the component."""
        return self.component.values

    @property
    def core(self) -> NetFtCore | None:
        """The component's decoder (None while unconfigured)."""
        return self.component.core

    @property
    def calibration_source(self) -> str:
        """Where the calibration came from (configure)."""
        return self.component.calibration_source

    def configure_device(self) -> None:
        """The component's configure; then the wrench publisher, ~/bias and the poll timer."""
        self.component.configure()
        self._wrench_pub = self.own(self.destroy_publisher, self.create_publisher(
            WrenchStamped, 'wrench', DEVICE_TOPIC_QOS))
        self._payload = (PayloadWriter(MessageCodec(WrenchStamped, {
            'header.frame_id': FT_SENSOR_LINK}), ['wrench']) if active_bus() else None)
        self.own(self.destroy_service, self.create_service(Trigger, '~/bias', self._on_bias))
        # One poll timer for the configured link; the component reads only while active.
        self.device_timer(1.0 / float(self.values['poll_rate_hz']), self._on_tick)
        (host, port), c = self.component.address, self.component.calibration_values
        self.get_logger().info(
            f'Net F/T at {host}:{port} answers; {c["counts_per_force"]:g} counts/N, '
            f'{c["counts_per_torque"]:g} counts/(N m), RDT {c["rdt_rate_hz"]:g} Hz '
            f'({self.calibration_source}); publishing wrench in {FT_SENSOR_LINK}')

    def activate_device(self) -> None:
        """Start real-time streaming."""
        self.component.activate()

    def put_device_back(self) -> list[str]:
        """Stop the stream (command 0)."""
        return self.component.put_back()

    def release_device(self) -> None:
        """Close the link."""
        self.component.release()

    def _on_tick(self) -> None:
        self.component.read(self.now_s())
        records = self.component.state().records
        if self._payload is not None:
            # In the robot loop: the CDR bytes written by struct, published raw and handed
            # to the controller's raw input as they are (no message object built, converted
            # and serialized again for each of the box's 500 records a second).
            for stamp_s, (force, torque) in records:
                self._wrench_pub.publish(self._payload.fill(round(stamp_s * 1e9), (*force,
                                                                                  *torque)))
            return
        for stamp_s, wrench in records:
            msg = WrenchStamped()
            msg.header.stamp = stamp(round(stamp_s * 1e9))
            msg.header.frame_id = FT_SENSOR_LINK
            (msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z), (
                msg.wrench.torque.x, msg.wrench.torque.y, msg.wrench.torque.z) = wrench
            self._wrench_pub.publish(msg)

    def _on_bias(self, request: Trigger.Request, response: Trigger.Response) -> Any:
        done = self.component.bias()
        response.success = done is not None
        response.message = done if done is not None else 'no record yet: nothing to bias'
        return response

    def device_report(self) -> Report:
        """The component's report."""
        report = self.component.report(self.now_s())
        return Report(LEVELS[report.level], report.message, dict(report.values))


def main(args: list[str] | None = None) -> None:
    """Run the netft_bridge node until SIGINT/SIGTERM; the stream is stopped first."""
    run_bridge(NetFtBridgeNode, args, 'netft_bridge')


if __name__ == '__main__':
    main()
