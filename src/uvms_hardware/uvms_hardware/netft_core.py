"""The Net F/T bridge's core: RDT datagrams in, a wrench in ft_sensor_link out; no ROS, no I/O.

Per poll of the socket::

    core = NetFtCore(counts_per_force=1e6, counts_per_torque=1e6, rdt_rate_hz=500.0)
    for stamp_s, (force, torque) in core.receive_all(datagrams, t_s, local_s, ages_s): ...
    core.bias()                            # the present reading becomes zero
    core.stale(t_s)                        # no record for timeout_s: nothing is published

``t_s`` is the steady clock (staleness), ``local_s`` the clock stamps are in, both read at
the poll, after the socket. Each record is stamped when the box sampled it: record n of the
stream (its rdt_sequence, unwrapped past 2^32) at n / ``rdt_rate_hz`` on the box's clock,
mapped into ``local_s`` through the offset and skew of `uvms_hardware.device_time`. These are
fitted on each poll's earliest (arrival - sample time), the arrival being the kernel's stamp
of the datagram (``ages_s``: how long before ``local_s`` each arrived); where the kernel
gives none, on the newest record against the poll's time, which polls in step with the box
leave up to one record period late. So the records of one poll lie one record period apart,
and a lost record (a sequence gap) advances time as the box did. A sequence that runs back by
more than `REORDER_RECORDS` is a new stream (the box restarted it): the clock is estimated
again. Without ``rdt_rate_hz``, or while the box's clock and ``local_s`` visibly run at
different rates (``DeviceClockEstimator.rates_agree``: a wrong rate, or a simulator's clock
beside a twin on wall time), every record is stamped with ``local_s``, and the report says so.

Frame and sign: the stack's wrist sensor reports in ft_sensor_link the wrench the end effector
exerts on the environment, x along the jaw's approach direction, which sensor.yaml takes as
the sensor's own z (axial) axis. ``rot_link_from_sensor`` turns the box's axes into
ft_sensor_link; its default maps sensor z to x, sensor x to y and sensor y to z (a right-handed
cyclic turn). The other two axes and the sign of ATI's reading relative to ours are not in the
documents: the default is an assumption to check at mounting (press the jaw tip along its
approach direction: +x must read positive), and the parameter changes it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from uvms_hardware import rdt_protocol as rdt
from uvms_hardware.device_time import DeviceClockEstimator
from uvms_hardware.errors import ProtocolError

Vector = tuple[float, float, float]
Wrench = tuple[Vector, Vector]
#: A sequence this many records behind the newest is a reordered record, further a new stream.
REORDER_RECORDS = 64
_WRAP = 1 << 32
#: Default rotation ft_sensor_link <- sensor, row-major: x_link = z_sensor, y = x_s, z = y_s.
DEFAULT_ROT_LINK_FROM_SENSOR = (0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0)


def _rotate(rot: Sequence[float], v: Vector) -> Vector:
    return (rot[0] * v[0] + rot[1] * v[1] + rot[2] * v[2],
            rot[3] * v[0] + rot[4] * v[1] + rot[5] * v[2],
            rot[6] * v[0] + rot[7] * v[1] + rot[8] * v[2])


def check_rotation(rot: Sequence[float]) -> None:
    """Refuse anything but a proper rotation (9 values, row-major, orthonormal, det +1).

    Raises:
        ValueError: Naming what is wrong.
    """
    if len(rot) != 9 or not all(math.isfinite(x) for x in rot):
        raise ValueError(f'rot_link_from_sensor: 9 finite values (row-major), got {list(rot)}')
    rows = [rot[0:3], rot[3:6], rot[6:9]]
    for i in range(3):
        for j in range(3):
            dot = sum(a * b for a, b in zip(rows[i], rows[j], strict=True))
            if abs(dot - (1.0 if i == j else 0.0)) > 1e-6:
                raise ValueError(f'rot_link_from_sensor {list(rot)} is not orthonormal')
    det = (rot[0] * (rot[4] * rot[8] - rot[5] * rot[7]) - rot[1] * (rot[3] * rot[8] - rot[5]
           * rot[6]) + rot[2] * (rot[3] * rot[7] - rot[4] * rot[6]))
    if det < 0.0:
        raise ValueError(f'rot_link_from_sensor {list(rot)} is a reflection (det -1)')


class NetFtCore:
    """Decodes records, counts losses and bad datagrams, biases, watches the stream.

    The calibration (counts per N, per N m) has no default: it is the box's, never assumed.
    """

    def __init__(self, counts_per_force: float, counts_per_torque: float,
                 rot_link_from_sensor: Sequence[float] = DEFAULT_ROT_LINK_FROM_SENSOR,
                 timeout_s: float = 0.1, rdt_rate_hz: float | None = None,
                 clock: DeviceClockEstimator | None = None) -> None:
        rdt.check_calibration(counts_per_force, counts_per_torque)
        if not timeout_s > 0.0:
            raise ValueError(f'watchdog_timeout_s = {timeout_s}: must be > 0')
        if rdt_rate_hz is not None and not (math.isfinite(rdt_rate_hz) and rdt_rate_hz > 0.0):
            raise ValueError(f'rdt_rate_hz = {rdt_rate_hz}: must be finite and > 0')
        check_rotation(rot_link_from_sensor)
        self.rdt_rate_hz = rdt_rate_hz
        #: The box's clock against ours (records' sequences at rdt_rate_hz vs polls).
        self.clock = clock or DeviceClockEstimator(window_s=5.0, bucket_s=0.1, reset_s=0.1)
        #: Times the rdt_sequence ran back: a new stream.
        self.stream_restarts = 0
        self._index: int | None = None
        self.counts_per_force = counts_per_force
        self.counts_per_torque = counts_per_torque
        self.rot = tuple(float(x) for x in rot_link_from_sensor)
        self.timeout_s = timeout_s
        self.records = 0
        self.lost = 0
        self.bad_datagrams = 0
        self.last_error = ''
        self.faulted_records = 0
        self.status = 0
        self.stale_episodes = 0
        self._sequence: int | None = None
        self._record_s = -math.inf
        self._stale = True
        self._raw: tuple[Vector, Vector] | None = None
        self._offset: tuple[Vector, Vector] = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))

    def receive(self, datagram: bytes, t_s: float) -> Wrench | None:
        """(force N, torque N m) in ft_sensor_link, bias removed; None for a bad datagram."""
        taken = self._take(datagram, t_s)
        return None if taken is None else taken[1]

    def receive_all(self, datagrams: Sequence[bytes], t_s: float, local_s: float,
                    ages_s: Sequence[float | None] | None = None
                    ) -> list[tuple[float, Wrench]]:
        """(stamp s on the local clock, wrench) of each good record of one poll, in order.

        ``ages_s``: how long before ``local_s`` each datagram arrived (s, the kernel's stamp;
        None where it gave none). The box's clock is then fitted on the poll's earliest
        (arrival - sample time), else on the newest record against ``local_s``.
        """
        ages = ages_s if ages_s is not None else [None] * len(datagrams)
        if len(ages) != len(datagrams):
            raise ValueError(f'{len(ages)} arrival ages for {len(datagrams)} datagrams')
        taken: list[tuple[int, Wrench, float | None]] = []
        for datagram, age_s in zip(datagrams, ages, strict=True):
            record = self._take(datagram, t_s)
            if record is not None:
                taken.append((*record, age_s))
        if not taken or self.rdt_rate_hz is None:
            return [(local_s, wrench) for _, wrench, _ in taken]
        period_s = 1.0 / self.rdt_rate_hz
        arrivals = [(local_s - max(0.0, age_s) - index * period_s, index)
                    for index, _, age_s in taken if age_s is not None]
        if arrivals:
            delay_s, index = min(arrivals)
            self.clock.add(index * period_s, index * period_s + delay_s)
        else:
            self.clock.add(max(index for index, _, _ in taken) * period_s, local_s)
        if not self.clock.rates_agree:
            return [(local_s, wrench) for _, wrench, _ in taken]
        return [(self.clock.to_local(index * period_s) or local_s, wrench)
                for index, wrench, _ in taken]

    def _index_of(self, sequence: int) -> int:
        """The record's place in the stream: its sequence unwrapped past 2^32."""
        if self._index is None or self._sequence is None:
            self._index, self._sequence = sequence, sequence
            return sequence
        step = (sequence - self._sequence) % _WRAP
        if step < _WRAP // 2:
            self.lost += rdt.lost_records(self._sequence, sequence)
            self._index += step
            self._sequence = sequence
            return self._index
        back = _WRAP - step
        if back <= REORDER_RECORDS:
            return self._index - back  # reordered on the way: from the past, nothing lost
        self.stream_restarts += 1  # the box began a new stream
        self.clock.restart(jumped=False)
        self._index, self._sequence = sequence, sequence
        return sequence

    def _take(self, datagram: bytes, t_s: float) -> tuple[int, Wrench] | None:
        try:
            record = rdt.decode_record(datagram)
        except ProtocolError as exc:
            self.bad_datagrams += 1
            self.last_error = str(exc)
            return None
        index = self._index_of(record.rdt_sequence)
        self.records += 1
        self.status = record.status
        if record.status:
            self.faulted_records += 1
        self._record_s, self._stale = t_s, False
        force, torque = rdt.wrench_from_counts(record.counts, self.counts_per_force,
                                               self.counts_per_torque)
        self._raw = (_rotate(self.rot, force), _rotate(self.rot, torque))
        (f, tq), (f0, t0) = self._raw, self._offset
        return index, ((f[0] - f0[0], f[1] - f0[1], f[2] - f0[2]),
                       (tq[0] - t0[0], tq[1] - t0[1], tq[2] - t0[2]))

    def bias(self) -> bool:
        """Take the last reading as zero from now on; False when no record has come yet."""
        if self._raw is None:
            return False
        self._offset = self._raw
        return True

    @property
    def offset(self) -> tuple[Vector, Vector]:
        """The bias subtracted (force N, torque N m) in ft_sensor_link."""
        return self._offset

    def stale(self, t_s: float) -> bool:
        """True when no record came for ``timeout_s`` (or none yet)."""
        stale = t_s - self._record_s > self.timeout_s
        if stale and not self._stale:
            self.stale_episodes += 1
        self._stale = stale
        return stale

    def age_s(self, t_s: float) -> float:
        """Seconds since the last record (inf before the first)."""
        return t_s - self._record_s

    def report(self, t_s: float) -> tuple[int, str, dict[str, object]]:
        """(level 0 OK / 1 WARN / 2 ERROR, message, values) for /diagnostics."""
        values: dict[str, object] = {
            'records': self.records, 'lost_records': self.lost,
            'bad_datagrams': self.bad_datagrams, 'status': f'{self.status:#010x}',
            'records_with_status_set': self.faulted_records,
            'stale_episodes': self.stale_episodes, 'record_age_s': self.age_s(t_s),
            'rdt_rate_hz': self.rdt_rate_hz, 'stream_restarts': self.stream_restarts,
            **self.clock.report()}
        if self.stale(t_s):
            return 2, f'no record for more than {self.timeout_s:g} s: not publishing', values
        if self.status:
            return 2, f'status word {self.status:#010x} set (meaning: ATI manual)', values
        if self.rdt_rate_hz is not None and not self.clock.rates_agree:
            return 1, (f'records do not arrive at rdt_rate_hz {self.rdt_rate_hz:g} on this '
                       "clock (the box's RDT output rate, or a simulator's clock): stamped at "
                       'arrival'), values
        if self.lost or self.bad_datagrams:
            return 1, (f'{self.lost} records lost, {self.bad_datagrams} bad datagrams '
                       'dropped'), values
        return 0, 'streaming', values
