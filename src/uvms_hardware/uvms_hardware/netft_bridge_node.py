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
"""

from __future__ import annotations

import urllib.request
from typing import Any

from geometry_msgs.msg import WrenchStamped
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.qos import QoSProfile, ReliabilityPolicy
from std_srvs.srv import Trigger
from uvms_common.diagnostics import ERROR, OK, WARN, Report

from uvms_hardware import rdt_protocol as rdt
from uvms_hardware.address import parse_host_port
from uvms_hardware.bridge_messages import stamp
from uvms_hardware.bridge_node import BridgeNode, run_bridge
from uvms_hardware.device_clock import stop_requested
from uvms_hardware.errors import HardwareError, ProtocolError
from uvms_hardware.hardware_config import HardwareConfigError, NetFtHardware, load_netft
from uvms_hardware.netft_core import DEFAULT_ROT_LINK_FROM_SENSOR, NetFtCore
from uvms_hardware.stop_report import write_stop_report
from uvms_hardware.transport import UdpLink, collect

_LEVELS = {0: OK, 1: WARN, 2: ERROR}
#: The frame of the wrist sensor's wrench (robot.urdf).
FT_SENSOR_LINK = 'ft_sensor_link'
#: While the stream is stale, the start request is repeated this often (s).
RESTART_PERIOD_S = 1.0
#: Largest calibration page read (bytes).
PAGE_BYTES = 1 << 20
#: What the box's page gives (rdt_protocol.BoxCalibration), each also a parameter.
BOX_VALUES = ('counts_per_force', 'counts_per_torque', 'rdt_rate_hz')

PARAMETERS: tuple[tuple[str, Any, str], ...] = (
    ('address', f'127.0.0.1:{rdt.RDT_PORT}', 'HOST[:PORT] of the Net F/T box (RDT over UDP)'),
    ('http_port', 80, "Port of the box's web page netftapi2.xml (calibration, RDT rate); its "
     'values win over the three below; 0: do not ask the box'),
    ('http_timeout_s', 1.0, 'Time the box has to answer each page request at configure (s)'),
    ('counts_per_force', 0.0, 'Calibration: counts per N when the box does not say (default: '
     'hardware.yaml netft; 0: not given)'),
    ('counts_per_torque', 0.0, 'Calibration: counts per N m when the box does not say (default: '
     'hardware.yaml netft; 0: not given)'),
    ('rdt_rate_hz', 0.0, "The box's RDT output rate when the box does not say (Hz): records "
     'are stamped at their sequence / rate (default: hardware.yaml netft; 0: not given)'),
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
        try:
            self.hardware: NetFtHardware | None = load_netft(self.robot_name)
            self.hardware_problem = ''
        except HardwareConfigError as exc:
            self.hardware, self.hardware_problem = None, str(exc)
        robot = {name: getattr(self.hardware, name) for name in
                 ('counts_per_force', 'counts_per_torque', 'rdt_rate_hz')
                 if self.hardware is not None and getattr(self.hardware, name) is not None}
        self.values = {name: self.declare_parameter(
            name, float(robot.get(name, default)) if name in robot else default,
            ParameterDescriptor(description=text, read_only=True)).value
            for name, default, text in PARAMETERS}
        #: Where the calibration came from (configure).
        self.calibration_source = ''
        self.core: NetFtCore | None = None
        self.link: UdpLink | None = None
        self._restart_s = 0.0
        self.start()

    def calibration(self, host: str) -> dict[str, float]:
        """Counts per N, per N m and the RDT rate: the box's page, else the parameters.

        Raises:
            NetFtBridgeError: Neither gives all three (both sources named).
        """
        v = self.values
        given = {name: float(v[name]) for name in BOX_VALUES if float(v[name]) > 0.0}
        where = (f'the parameters (defaults: {self.hardware.source} netft)'
                 if self.hardware is not None else f'the parameters ({self.hardware_problem})')
        box: dict[str, float] = {}
        url, box_problem = '', 'was not asked (http_port 0)'
        if int(v['http_port']) > 0:
            url = f'http://{host}:{int(v["http_port"])}/netftapi2.xml'
            try:
                page = read_calibration(url, float(v['http_timeout_s']))
            except (OSError, ProtocolError) as exc:
                box_problem = f'{url} did not answer: {exc}'
            else:
                box = {name: getattr(page, name) for name in BOX_VALUES
                       if getattr(page, name) is not None}
                box_problem = f'{url} gave no ' + ', '.join(n for n in BOX_VALUES if n not in box)
        for name, value in box.items():
            if name in given and abs(given[name] - value) > 1e-9 * value:
                self.get_logger().warning(f'{name}: the box says {value:g}, {where} '
                                          f"{given[name]:g}: the box's is used")
        values = {**given, **box}
        missing = [name for name in BOX_VALUES if name not in values]
        if missing:
            raise NetFtBridgeError(
                f'no {", ".join(missing)} for the Net F/T at {host}: the box\'s page '
                f'{box_problem}, and {where} give none; never assumed: set them from the '
                "box's page (cfgcpf, cfgcpt, comrdtrate)")
        sources = {name: url if name in box else where for name in BOX_VALUES}
        self.calibration_source = (where if not box else url if len(box) == len(BOX_VALUES)
                                   else '; '.join(f'{n} from {w}' for n, w in sources.items()))
        if len(box) < len(BOX_VALUES):
            self.calibration_source += f" (the box's page {box_problem})"
        return values

    def configure_device(self) -> None:
        """Check parameters, find the calibration, open the link, see one record, publish."""
        v = self.values
        host, port = parse_host_port(str(v['address']), rdt.RDT_PORT)
        self.calibration_source = ''
        calibration = self.calibration(host)
        core = NetFtCore(calibration['counts_per_force'], calibration['counts_per_torque'],
                         [float(x) for x in v['rot_link_from_sensor']],
                         float(v['watchdog_timeout_s']), calibration['rdt_rate_hz'])
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
        # One poll timer for the configured link; it reads only while active.
        self.device_timer(1.0 / float(v['poll_rate_hz']), self._on_tick)
        c = calibration
        self.get_logger().info(
            f'Net F/T at {host}:{port} answers; {c["counts_per_force"]:g} counts/N, '
            f'{c["counts_per_torque"]:g} counts/(N m), RDT {c["rdt_rate_hz"]:g} Hz '
            f'({self.calibration_source}); publishing wrench in {FT_SENSOR_LINK}')

    def activate_device(self) -> None:
        """Start real-time streaming and poll the socket."""
        assert self.link is not None
        self.link.read()  # records still in flight from the configure check
        self.link.send(rdt.encode_request(rdt.COMMAND_START_REALTIME))
        self._restart_s = self.now_s()

    def put_device_back(self) -> list[str]:
        """Stop the stream (command 0)."""
        if self.link is not None:
            self.link.send(rdt.encode_request(rdt.COMMAND_STOP))
            done = 'RDT stream stopped (command 0 sent; RDT has no acknowledgement)'
            self.get_logger().info(f'put back: {done}')
            write_stop_report(self.get_name(), done, [])
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
        datagrams = link.read_datagrams()
        # Read after the socket: every record had arrived by then (a delay never negative).
        local_s = self.get_clock().now().nanoseconds * 1e-9
        bad = core.bad_datagrams
        for stamp_s, wrench in core.receive_all(datagrams, t_s, local_s):
            msg = WrenchStamped()
            msg.header.stamp = stamp(round(stamp_s * 1e9))
            msg.header.frame_id = FT_SENSOR_LINK
            (msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z), (
                msg.wrench.torque.x, msg.wrench.torque.y, msg.wrench.torque.z) = wrench
            self._wrench_pub.publish(msg)
        if core.bad_datagrams > bad:
            self.get_logger().warning(f'bad datagram dropped: {core.last_error}',
                                      throttle_duration_sec=5.0)
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
        return Report(_LEVELS[level], message,
                      {**values, 'calibration_source': self.calibration_source,
                       'counts_per_force': self.core.counts_per_force,
                       'counts_per_torque': self.core.counts_per_torque})


def read_calibration(url: str, timeout_s: float) -> rdt.BoxCalibration:
    """The box's calibration from its pages: the active configuration's, as ATI's demo reads it.

    Raises:
        OSError: No answer (urllib's errors are OSErrors).
        ProtocolError: A page that does not give it.
    """
    opener = urllib.request.build_opener(urllib.request.ProxyHandler({}))  # the box, no proxy
    with opener.open(url, timeout=timeout_s) as answer:
        page = answer.read(PAGE_BYTES)
    index = rdt.active_configuration(page)
    if index is not None:
        with opener.open(f'{url}?index={index}', timeout=timeout_s) as answer:
            page = answer.read(PAGE_BYTES)
    return rdt.calibration_from_netftapi2(page)


def main(args: list[str] | None = None) -> None:
    """Run the netft_bridge node until SIGINT/SIGTERM; the stream is stopped first."""
    run_bridge(NetFtBridgeNode, args, 'netft_bridge')


if __name__ == '__main__':
    main()
