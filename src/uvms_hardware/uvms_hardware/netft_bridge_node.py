"""The ``netft_bridge`` node: an ATI Net F/T's RDT stream as ``wrench`` in ``ft_sensor_link``.

A managed node (``autostart``). configure opens the UDP link to ``address`` and checks that the
box answers a start request with a record within ``answer_timeout_s`` (then stops it again);
activate starts real-time streaming (command 2, infinite samples); each record becomes a
``geometry_msgs/WrenchStamped`` in ``ft_sensor_link`` (the simulator's wrist-sensor topic and
convention, ``uvms_hardware.netft_core``); ``~/bias`` (std_srvs/Trigger) zeroes the present
reading (in the bridge: ATI's own bias command is not in the documents). Watchdog: no record
for ``watchdog_timeout_s`` and publishing stops (there is nothing to publish), /diagnostics
turns ERROR, and the start request is sent again once a second. deactivate, shutdown, SIGINT
and SIGTERM send the stop command (command 0). /diagnostics: records, lost records (from
rdt_sequence gaps), bad datagrams, the status word.
"""

from __future__ import annotations

from typing import Any

from geometry_msgs.msg import WrenchStamped
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.qos import QoSProfile, ReliabilityPolicy
from std_srvs.srv import Trigger
from uvms_common.diagnostics import ERROR, OK, WARN, Report

from uvms_hardware import rdt_protocol as rdt
from uvms_hardware.address import parse_host_port
from uvms_hardware.bridge_node import BridgeNode, run_bridge
from uvms_hardware.device_clock import stop_requested
from uvms_hardware.errors import HardwareError
from uvms_hardware.netft_core import DEFAULT_ROT_LINK_FROM_SENSOR, NetFtCore
from uvms_hardware.transport import UdpLink, collect

_LEVELS = {0: OK, 1: WARN, 2: ERROR}
#: The frame of the wrist sensor's wrench (robot.urdf).
FT_SENSOR_LINK = 'ft_sensor_link'
#: While the stream is stale, the start request is repeated this often (s).
RESTART_PERIOD_S = 1.0

PARAMETERS: tuple[tuple[str, Any, str], ...] = (
    ('address', f'127.0.0.1:{rdt.RDT_PORT}', 'HOST[:PORT] of the Net F/T box (RDT over UDP)'),
    ('counts_per_force', rdt.DEFAULT_COUNTS_PER_FORCE, 'Calibration: counts per N'),
    ('counts_per_torque', rdt.DEFAULT_COUNTS_PER_TORQUE, 'Calibration: counts per N m'),
    ('rot_link_from_sensor', list(DEFAULT_ROT_LINK_FROM_SENSOR),
     'Rotation ft_sensor_link <- sensor axes, row-major (default: sensor z along the jaw)'),
    ('watchdog_timeout_s', 0.1, 'No record for this long: stop publishing, diagnostics (s)'),
    ('poll_rate_hz', 500.0, 'How often the socket is read; every record is published (Hz)'),
    ('answer_timeout_s', 0.5, 'Time the box has to send its first record at configure (s)'),
    ('startup_wait_s', 10.0,
     'While the box sends nothing, configure asks again for this long (s): it may come up '
     'after the bridge (launch order); 0 asks once'),
)


class NetFtBridgeError(HardwareError):
    """A parameter of the bridge is invalid or the box cannot be configured."""


class NetFtBridgeNode(BridgeNode):
    """ATI Net F/T bridge: RDT records in, wrench and diagnostics out."""

    error_type = NetFtBridgeError
    diagnostics_task = 'netft'

    def __init__(self, **kwargs: Any) -> None:
        super().__init__('netft_bridge', **kwargs)
        self.values = {name: self.declare_parameter(
            name, default, ParameterDescriptor(description=text, read_only=True)).value
            for name, default, text in PARAMETERS}
        self.core: NetFtCore | None = None
        self.link: UdpLink | None = None
        self._restart_s = 0.0
        self.start()

    def configure_device(self) -> None:
        """Check parameters, open the link, see one record, create publisher and service."""
        v = self.values
        host, port = parse_host_port(str(v['address']), rdt.RDT_PORT)
        core = NetFtCore(float(v['counts_per_force']), float(v['counts_per_torque']),
                         [float(x) for x in v['rot_link_from_sensor']],
                         float(v['watchdog_timeout_s']))
        if not float(v['poll_rate_hz']) > 0.0:
            raise NetFtBridgeError(f'poll_rate_hz = {v["poll_rate_hz"]}: must be > 0')
        self.link = link = UdpLink(host, port)
        timeout_s = float(v['answer_timeout_s'])
        deadline_s = self.now_s() + float(v['startup_wait_s'])
        while True:
            link.send(rdt.encode_request(rdt.COMMAND_START_REALTIME))
            seen = collect(link, lambda chunk: [1] if chunk and not len(chunk) % rdt.RECORD_BYTES
                           else [], [1], timeout_s)
            link.send(rdt.encode_request(rdt.COMMAND_STOP))
            if seen or self.now_s() >= deadline_s or stop_requested():
                break
            self.get_logger().info(f'no record from {host}:{port} yet: asking again',
                                   throttle_duration_sec=2.0)
        if not seen:
            raise NetFtBridgeError(f'no RDT record from {host}:{port} within {timeout_s:g} s')
        self.core = core
        qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        self._wrench_pub = self.own(self.destroy_publisher,
                                    self.create_publisher(WrenchStamped, 'wrench', qos))
        self.own(self.destroy_service, self.create_service(Trigger, '~/bias', self._on_bias))
        self.get_logger().info(f'Net F/T at {host}:{port} answers; publishing wrench in '
                               f'{FT_SENSOR_LINK}')

    def activate_device(self) -> None:
        """Start real-time streaming and poll the socket."""
        assert self.link is not None
        self.link.read()  # records still in flight from the configure check
        self.link.send(rdt.encode_request(rdt.COMMAND_START_REALTIME))
        self._restart_s = self.now_s()
        self._timer = self.device_timer(1.0 / float(self.values['poll_rate_hz']), self._on_tick)

    def put_device_back(self) -> list[str]:
        """Stop the stream (command 0)."""
        if self.link is not None:
            self.link.send(rdt.encode_request(rdt.COMMAND_STOP))
        return []

    def release_device(self) -> None:
        """Close the link."""
        if self.link is not None:
            self.link.close()
        self.link, self.core = None, None

    def _on_tick(self) -> None:
        core, link = self.core, self.link
        if core is None or link is None or not self.device_active:
            return
        t_s = self.now_s()
        for datagram in link.read_datagrams():
            wrench = core.receive(datagram, t_s)
            if wrench is None:
                self.get_logger().warning(f'bad datagram dropped: {core.last_error}',
                                          throttle_duration_sec=5.0)
                continue
            msg = WrenchStamped()
            msg.header.stamp = self.get_clock().now().to_msg()
            msg.header.frame_id = FT_SENSOR_LINK
            (msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z), (
                msg.wrench.torque.x, msg.wrench.torque.y, msg.wrench.torque.z) = wrench
            self._wrench_pub.publish(msg)
        if core.stale(t_s) and t_s - self._restart_s >= RESTART_PERIOD_S:
            self._restart_s = t_s
            link.send(rdt.encode_request(rdt.COMMAND_START_REALTIME))
            self.get_logger().warning(f'no record for {core.age_s(t_s):.2f} s: start requested '
                                      'again', throttle_duration_sec=5.0)

    def _on_bias(self, request: Trigger.Request, response: Trigger.Response) -> Any:
        if self.core is None or not self.core.bias():
            response.success, response.message = False, 'no record yet: nothing to bias'
            return response
        force, torque = self.core.offset
        response.success = True
        response.message = (f'bias force {[round(f, 4) for f in force]} N, torque '
                            f'{[round(t, 4) for t in torque]} N m (ft_sensor_link)')
        return response

    def device_report(self) -> Report:
        """Records, lost records, bad datagrams and the status word; OK while not streaming."""
        if self.core is None:
            return Report(WARN, 'not configured', {})
        if not self.device_active:
            return Report(OK, 'not streaming', {})
        level, message, values = self.core.report(self.now_s())
        return Report(_LEVELS[level], message, values)


def main(args: list[str] | None = None) -> None:
    """Run the netft_bridge node until SIGINT/SIGTERM; the stream is stopped first."""
    run_bridge(NetFtBridgeNode, args, 'netft_bridge')


if __name__ == '__main__':
    main()
