"""Codec of ATI Net F/T's RDT (raw data transfer) over UDP: bytes in, numbers out.

Source: shared/robots/bluerov2_heavy_alpha5.md, "ATI Net F/T (RDT over UDP)" (ATI's
NetFTRDTCommand / NetFTRDTPacket sample code). All fields are big-endian::

    request (8 bytes)   uint16 header 0x1234, uint16 command, uint32 sample count (0: infinite)
    record (36 bytes)   uint32 rdt_sequence, uint32 ft_sequence, uint32 status,
                        int32 Fx, Fy, Fz, Tx, Ty, Tz (counts)

Force = counts / counts_per_force, torque = counts / counts_per_torque: the box's calibration
says, on its web page. ATI's Net F/T Java demo (com.atiia.automation.sensors) reads
``/netftapi2.xml`` for the active configuration ``setcfgsel``, then
``/netftapi2.xml?index=<it>`` for its ``cfgcpf`` and ``cfgcpt`` (counts per force and per
torque unit) and ``comrdtrate`` (the RDT output rate); other code reading ATI boxes takes the
units from ``scfgfu`` and ``scfgtu`` (`active_configuration`, `calibration_from_netftapi2`).
1,000,000 counts per unit is ATI's NetFTRDTPacket sample code's own assumption, never the
bridge's. The meaning of the status bits is not in the document: they are reported as a
number, non-zero taken as a fault (assumed, for docs/hardware.md). Whether sequences wrap at
2^32 is not stated either; `lost_records` assumes they do.
Counts are int32 on the wire, so a record cannot carry a non-finite number: any record decodes
to finite forces for a finite positive calibration (at most 2^31 counts, i.e. 2147 N at
1e6 counts per N); a calibration that is not finite and positive is refused.
"""

from __future__ import annotations

import math
import struct
import xml.etree.ElementTree as ET
from dataclasses import dataclass

from uvms_hardware.errors import ProtocolError

#: Net F/T's RDT UDP port.
RDT_PORT = 49152
#: First field of every request.
REQUEST_HEADER = 0x1234
#: Commands of the document (others are in ATI's manual, not used here).
COMMAND_STOP = 0
COMMAND_START_REALTIME = 2
#: Sample count meaning "until stopped".
INFINITE_SAMPLES = 0
#: ATI's sample code's calibration (counts per N, counts per N m): the twin's, never assumed
#: by the bridge (which reads the box's page or the hardware file).
DEFAULT_COUNTS_PER_FORCE = 1_000_000.0
DEFAULT_COUNTS_PER_TORQUE = 1_000_000.0
#: N per force unit and N m per torque unit a box may be set to (``scfgfu``, ``scfgtu``;
#: compared without case). Exact by definition of the units (lbf = 4.4482216152605 N, in =
#: 0.0254 m, kgf = 9.80665 N); the spellings are those seen in code reading ATI boxes, and any
#: other is refused rather than guessed.
FORCE_UNITS_N = {'n': 1.0, 'kn': 1000.0, 'lbf': 4.4482216152605, 'klbf': 4448.2216152605,
                 'g': 0.00980665, 'kg': 9.80665, 'kgf': 9.80665}
TORQUE_UNITS_N_M = {'n-m': 1.0, 'nm': 1.0, 'n-mm': 0.001, 'kn-m': 1000.0,
                    'lbf-in': 4.4482216152605 * 0.0254, 'lbf-ft': 4.4482216152605 * 0.3048,
                    'klbf-in': 4448.2216152605 * 0.0254, 'g-cm': 0.00980665 * 0.01,
                    'kg-cm': 9.80665 * 0.01}

_REQUEST = struct.Struct('>HHI')
_RECORD = struct.Struct('>III6i')
REQUEST_BYTES = _REQUEST.size
RECORD_BYTES = _RECORD.size
_SEQUENCE_MODULUS = 1 << 32


@dataclass(frozen=True)
class Request:
    """A decoded request: command and sample count."""

    command: int
    sample_count: int


@dataclass(frozen=True)
class Record:
    """One RDT record: sequences, status word and the six raw counts (Fx Fy Fz Tx Ty Tz)."""

    rdt_sequence: int
    ft_sequence: int
    status: int
    counts: tuple[int, int, int, int, int, int]


@dataclass(frozen=True)
class BoxCalibration:
    """What a box's ``netftapi2.xml`` says: counts per N and per N m, its RDT rate (Hz)."""

    counts_per_force: float
    counts_per_torque: float
    rdt_rate_hz: float | None


def _fields(text: str | bytes) -> dict[str, str]:
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise ProtocolError(f'netftapi2.xml is not XML: {exc}') from exc
    return {element.tag.rsplit('}', 1)[-1].lower(): (element.text or '').strip()
            for element in root.iter()}


def active_configuration(text: str | bytes) -> int | None:
    """The active configuration's index (``setcfgsel``) of a ``netftapi2.xml``, if given.

    Raises:
        ProtocolError: Not XML, or a ``setcfgsel`` that is no whole number.
    """
    value = _fields(text).get('setcfgsel')
    if value is None:
        return None
    if not value.isdigit():
        raise ProtocolError(f'netftapi2.xml: <setcfgsel> = {value!r}: expected an index')
    return int(value)


def calibration_from_netftapi2(text: str | bytes) -> BoxCalibration:
    """The calibration of a box's ``/netftapi2.xml`` page, converted to N and N m.

    Raises:
        ProtocolError: Not XML, a field missing or not a positive number, or a unit not in
            `FORCE_UNITS_N` / `TORQUE_UNITS_N_M` (named).
    """
    fields = _fields(text)

    def positive(tag: str) -> float:
        try:
            value = float(fields[tag])
        except (KeyError, ValueError):
            raise ProtocolError(f'netftapi2.xml: <{tag}> = {fields.get(tag)!r}: expected a '
                                'number') from None
        if not (math.isfinite(value) and value > 0.0):
            raise ProtocolError(f'netftapi2.xml: <{tag}> = {value}: expected > 0')
        return value

    def unit(tag: str, table: dict[str, float]) -> float:
        name = fields.get(tag)
        if name is None or name.lower() not in table:
            raise ProtocolError(f'netftapi2.xml: <{tag}> = {name!r}: not a unit this bridge '
                                f'knows ({", ".join(sorted(table))})')
        return table[name.lower()]

    rate = positive('comrdtrate') if 'comrdtrate' in fields else None
    return BoxCalibration(positive('cfgcpf') / unit('scfgfu', FORCE_UNITS_N),
                          positive('cfgcpt') / unit('scfgtu', TORQUE_UNITS_N_M), rate)


def encode_request(command: int, sample_count: int = INFINITE_SAMPLES) -> bytes:
    """The 8-byte request: header 0x1234, ``command``, ``sample_count``."""
    return _REQUEST.pack(REQUEST_HEADER, command, sample_count)


def decode_request(datagram: bytes) -> Request:
    """The request of an 8-byte datagram.

    Raises:
        ProtocolError: Another length, or a header other than 0x1234.
    """
    if len(datagram) != REQUEST_BYTES:
        raise ProtocolError(f'RDT request of {len(datagram)} bytes, expected {REQUEST_BYTES}')
    header, command, count = _REQUEST.unpack(datagram)
    if header != REQUEST_HEADER:
        raise ProtocolError(f'RDT request header {header:#06x}, expected {REQUEST_HEADER:#06x}')
    return Request(command, count)


def encode_record(record: Record) -> bytes:
    """The 36-byte datagram of a record (what the box sends; the twin uses it)."""
    return _RECORD.pack(record.rdt_sequence, record.ft_sequence, record.status, *record.counts)


def decode_record(datagram: bytes) -> Record:
    """The record of a 36-byte datagram.

    Raises:
        ProtocolError: A datagram shorter or longer than 36 bytes.
    """
    if len(datagram) != RECORD_BYTES:
        raise ProtocolError(f'RDT record of {len(datagram)} bytes, expected {RECORD_BYTES}')
    rdt, ft, status, *counts = _RECORD.unpack(datagram)
    fx, fy, fz, tx, ty, tz = counts
    return Record(rdt, ft, status, (fx, fy, fz, tx, ty, tz))


def counts_from_wrench(force_n: tuple[float, float, float], torque_n_m: tuple[float, float, float],
                       counts_per_force: float = DEFAULT_COUNTS_PER_FORCE,
                       counts_per_torque: float = DEFAULT_COUNTS_PER_TORQUE,
                       ) -> tuple[int, int, int, int, int, int]:
    """Counts of a wrench (rounded to the nearest count), as the box would send it."""
    fx, fy, fz = (round(f * counts_per_force) for f in force_n)
    tx, ty, tz = (round(t * counts_per_torque) for t in torque_n_m)
    return fx, fy, fz, tx, ty, tz


def check_calibration(counts_per_force: float, counts_per_torque: float) -> None:
    """Refuse counts per N or per N m that are not finite and positive.

    Raises:
        ProtocolError: Naming both values.
    """
    if not all(math.isfinite(c) and c > 0.0 for c in (counts_per_force, counts_per_torque)):
        raise ProtocolError(f'counts per force {counts_per_force} / per torque '
                            f'{counts_per_torque}: both must be finite and > 0')


def wrench_from_counts(counts: tuple[int, ...], counts_per_force: float = DEFAULT_COUNTS_PER_FORCE,
                       counts_per_torque: float = DEFAULT_COUNTS_PER_TORQUE,
                       ) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """(force N, torque N m) of six counts Fx Fy Fz Tx Ty Tz, in the sensor's own axes.

    Raises:
        ProtocolError: Not six counts, or a calibration that is not positive.
    """
    if len(counts) != 6:
        raise ProtocolError(f'{len(counts)} counts, expected 6 (Fx Fy Fz Tx Ty Tz)')
    check_calibration(counts_per_force, counts_per_torque)
    fx, fy, fz, tx, ty, tz = counts
    return ((fx / counts_per_force, fy / counts_per_force, fz / counts_per_force),
            (tx / counts_per_torque, ty / counts_per_torque, tz / counts_per_torque))


def lost_records(previous_sequence: int | None, sequence: int) -> int:
    """Records lost between two received RDT sequence numbers (0 for the first or a repeat).

    >>> lost_records(None, 7), lost_records(7, 8), lost_records(7, 10), lost_records(2**32 - 1, 1)
    (0, 0, 2, 1)
    """
    if previous_sequence is None:
        return 0
    step = (sequence - previous_sequence) % _SEQUENCE_MODULUS
    # A step of half the range or more is a record from the past (reordered): nothing lost.
    return step - 1 if 0 < step < _SEQUENCE_MODULUS // 2 else 0
