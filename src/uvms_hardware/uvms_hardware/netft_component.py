"""The ATI Net F/T as a hardware component: RDT records in, wrenches in ft_sensor_link out.

No ROS (``netft_bridge_node`` wraps it in a managed node). configure finds the calibration,
opens the UDP link to ``address`` and checks that the box answers a start request with a
record within ``answer_timeout_s`` (then stops it again); activate starts real-time streaming
(command 2, infinite samples); `read` drains the socket without waiting and decodes every
record (`uvms_hardware.netft_core`); `bias` zeroes the present reading (in the component:
ATI's own bias command is not in the documents). Watchdog: no record for
``watchdog_timeout_s`` and `state` is not fresh (nothing new to publish), the report is
ERROR, and the start request is sent again once a second. `put_back` sends the stop command
(command 0)::

    netft = NetFtComponent(values, hardware, '', clock=time.monotonic)
    netft.configure(); netft.activate()
    netft.read(now_s); for stamp_s, (force, torque) in netft.state().records: ...
    netft.put_back(); netft.release()

Calibration, never assumed: counts per force and per torque and the RDT output rate come from
the box's own page (``http://HOST:http_port/netftapi2.xml``, the active configuration, as
ATI's demo code reads it; `uvms_hardware.rdt_protocol`), else from ``values``, whose defaults
are the robot's ``hardware.yaml`` ``netft`` section; with neither, configure is refused naming
both.
"""

from __future__ import annotations

import time
import urllib.request
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from uvms_hardware import latency_probe
from uvms_hardware import rdt_protocol as rdt
from uvms_hardware.address import parse_host_port
from uvms_hardware.component import (
    OK,
    WARN,
    ComponentReport,
    HardwareComponent,
    LogFn,
    Throttle,
    python_log,
)
from uvms_hardware.errors import HardwareError, ProtocolError
from uvms_hardware.hardware_config import NetFtHardware
from uvms_hardware.netft_core import DEFAULT_ROT_LINK_FROM_SENSOR, NetFtCore, Wrench
from uvms_hardware.stop_report import write_stop_report
from uvms_hardware.transport import UdpLink, collect

#: While the stream is stale, the start request is repeated this often (s).
RESTART_PERIOD_S = 1.0
#: Largest calibration page read (bytes).
PAGE_BYTES = 1 << 20
#: What the box's page gives (rdt_protocol.BoxCalibration), each also a parameter.
BOX_VALUES = ('counts_per_force', 'counts_per_torque', 'rdt_rate_hz')

#: (name, default, description) of each setting: the bridge node's parameters.
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


@dataclass(frozen=True)
class NetFtState:
    """What the Net F/T gave at the last `NetFtComponent.read`.

    Attributes:
        records: (stamp s on the local clock, (force N, torque N m) in ft_sensor_link) of each
            record that read took, oldest first (each record once).
        wrench: The newest record's wrench, None before the first.
        fresh: False while the stream is stale (no record for ``watchdog_timeout_s``).
    """

    records: tuple[tuple[float, Wrench], ...]
    wrench: Wrench | None
    fresh: bool


class NetFtComponent(HardwareComponent):
    """ATI Net F/T over RDT (UDP): a sensor component."""

    def __init__(self, values: Mapping[str, Any], hardware: NetFtHardware | None = None,
                 hardware_problem: str = '', name: str = 'netft_bridge',
                 clock: Callable[[], float] = time.monotonic,
                 local_clock: Callable[[], float] | None = None, log: LogFn = python_log,
                 stop_requested: Callable[[], bool] = lambda: False) -> None:
        """A component over the box ``values['address']`` (not contacted until configure).

        Args:
            values: Every setting of `PARAMETERS` by name.
            hardware: The robot's hardware.yaml ``netft`` section (named in messages).
            hardware_problem: Why there is no section (named in a refusal).
            name: The node's name (stop report).
            clock: The steady clock (s): watchdog, restarts, configure's waits.
            local_clock: The clock stamps are in (s; default ``clock``).
            log: Where messages go.
            stop_requested: True once the process is asked to stop (ends configure's waits).
        """
        super().__init__()
        self.values = dict(values)
        self.hardware, self.hardware_problem = hardware, hardware_problem
        self.name = name
        self.clock, self.local_clock = clock, local_clock or clock
        self.log, self.stop_requested = log, stop_requested
        #: Where the calibration came from (configure).
        self.calibration_source = ''
        self.calibration_values: dict[str, float] = {}
        self.core: NetFtCore | None = None
        self.link: UdpLink | None = None
        self.address = ('', 0)
        self._restart_s = 0.0
        self._records: tuple[tuple[float, Wrench], ...] = ()
        self._latest: Wrench | None = None
        self._bad_throttle, self._stale_throttle = Throttle(5.0), Throttle(5.0)

    def calibration(self, host: str) -> dict[str, float]:
        """Counts per N, per N m and the RDT rate: the box's page, else ``values``.

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
                self.log('warning', f'{name}: the box says {value:g}, {where} '
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

    # -- lifecycle ---------------------------------------------------------------------------
    def configure(self) -> None:
        """Check the settings, find the calibration, open the link, see one record.

        Raises:
            NetFtBridgeError: No calibration, a bad setting, or no record from the box.
            ValueError: A setting out of range (``NetFtCore``'s checks).
        """
        v = self.values
        host, port = self.address = parse_host_port(str(v['address']), rdt.RDT_PORT)
        self.calibration_source = ''
        self.calibration_values = calibration = self.calibration(host)
        core = NetFtCore(calibration['counts_per_force'], calibration['counts_per_torque'],
                         [float(x) for x in v['rot_link_from_sensor']],
                         float(v['watchdog_timeout_s']), calibration['rdt_rate_hz'])
        if not float(v['poll_rate_hz']) > 0.0:
            raise NetFtBridgeError(f'poll_rate_hz = {v["poll_rate_hz"]}: must be > 0')
        self.configured = True
        self.link = link = UdpLink(host, port)
        timeout_s = float(v['answer_timeout_s'])
        deadline_s = self.clock() + float(v['startup_wait_s'])
        asked = Throttle(2.0)
        while True:
            link.send(rdt.encode_request(rdt.COMMAND_START_REALTIME))
            seen = collect(link, lambda chunk: [1] if chunk and not len(chunk) % rdt.RECORD_BYTES
                           else [], [1], timeout_s)
            link.send(rdt.encode_request(rdt.COMMAND_STOP))
            if seen or self.clock() >= deadline_s or self.stop_requested():
                break
            if asked(self.clock()):
                self.log('info', f'no record from {host}:{port} yet: asking again')
        if not seen:
            raise NetFtBridgeError(f'no RDT record from {host}:{port} within {timeout_s:g} s')
        self.core = core

    def activate(self) -> None:
        """Start real-time streaming (command 2, infinite samples)."""
        assert self.link is not None
        self.link.read()  # records still in flight from the configure check
        self.link.send(rdt.encode_request(rdt.COMMAND_START_REALTIME))
        self._restart_s = self.clock()
        self._records = ()
        super().activate()

    def put_back(self) -> list[str]:
        """Stop the stream (command 0): said on the log and in the stop report."""
        self.active = False
        self._records = ()
        if self.link is not None:
            self.link.send(rdt.encode_request(rdt.COMMAND_STOP))
            done = 'RDT stream stopped (command 0 sent; RDT has no acknowledgement)'
            self.log('info', f'put back: {done}')
            write_stop_report(self.name, done, [])
        return []

    def release(self) -> None:
        """Close the link."""
        if self.link is not None:
            self.link.close()
        self.link, self.core = None, None
        self._records, self._latest = (), None
        super().release()

    # -- the loop ----------------------------------------------------------------------------
    def read(self, now_s: float) -> None:
        """Every record waiting, decoded and stamped; the start request again while stale.

        Only while active (an inactive box streams nothing); never waits.
        """
        core, link = self.core, self.link
        self._records = ()
        if core is None or link is None or not self.active:
            return
        stamped = link.read_stamped()
        # Both read after the socket: every record had arrived by then. The kernel's clock
        # (CLOCK_REALTIME) first: each datagram's age is taken back from local_s, read later,
        # so a pause between the two reads makes an arrival later than it was, never earlier
        # (an earlier one would pull the minimum-delay fit below every true delay).
        wall_s = time.time()
        local_s = self.local_clock()
        datagrams = [datagram for datagram, _ in stamped]
        ages_s = [None if arrival_s is None else wall_s - arrival_s for _, arrival_s in stamped]
        if latency_probe.enabled():  # each record's RDT sequence, for bench_twin_latency
            for datagram in datagrams:
                latency_probe.note('ftrx', 0, int.from_bytes(datagram[:4], 'big'))
        bad = core.bad_datagrams
        self._records = tuple(core.receive_all(datagrams, now_s, local_s, ages_s))
        if self._records:
            self._latest = self._records[-1][1]
        if core.bad_datagrams > bad and self._bad_throttle(now_s):
            self.log('warning', f'bad datagram dropped: {core.last_error}')
        if core.stale(now_s) and now_s - self._restart_s >= RESTART_PERIOD_S:
            self._restart_s = now_s
            link.send(rdt.encode_request(rdt.COMMAND_START_REALTIME))
            if self._stale_throttle(now_s):
                self.log('warning', f'no record for {core.age_s(now_s):.2f} s: start requested '
                         'again')

    def state(self) -> NetFtState:
        """The records of the last read; ``fresh`` False once the stream went stale."""
        core = self.core
        fresh = bool(self._records) or (core is not None and self.active
                                        and not core.stale(self.clock()))
        return NetFtState(self._records, self._latest if fresh else None, fresh)

    def bias(self) -> str | None:
        """Take the present reading as zero; what was subtracted, or None (no record yet)."""
        if self.core is None or not self.core.bias():
            return None
        force, torque = self.core.offset
        return (f'bias force {[round(f, 4) for f in force]} N, torque '
                f'{[round(t, 4) for t in torque]} N m (ft_sensor_link)')

    def report(self, now_s: float) -> ComponentReport:
        """Records, lost records, bad datagrams and the status word; OK while not streaming."""
        if self.core is None:
            return ComponentReport(WARN, 'not configured', {})
        if not self.active:
            return ComponentReport(OK, 'not streaming', {})
        level, message, values = self.core.report(now_s)
        return ComponentReport(level, message, {
            **values, 'calibration_source': self.calibration_source,
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
