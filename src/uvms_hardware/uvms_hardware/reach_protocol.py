"""Codec of the Reach System communication protocol (Reach Alpha 5): bytes in, numbers out.

Source: "Reach System communication protocol" v1.12.5 (Reach-Robotics/reach_robotics_sdk), as
summarised in shared/robots/bluerov2_heavy_alpha5.md, "Hardware protocols". A packet is::

    raw   = DATA | PACKET_ID | DEVICE_ID | LENGTH | CRC     LENGTH = len(DATA) + 4
    frame = COBS(raw) | 0x00                               raw is 64 bytes at most

CRC-8 over DATA | PACKET_ID | DEVICE_ID | LENGTH: polynomial 0x4D (0x14D), input and output
reflected, register init 0x00, final XOR 0xFF. crcmod takes its ``initCrc`` as the register
init XORed with the final XOR, hence ``initCrc=0xFF`` below; the document's four vectors
(test/unit/hardware/test_reach_protocol.py) agree with that and not with ``initCrc=0x00``.
Data are uint8 or float32, little-endian.

Units: the joints speak rad, rad/s and mA; the jaws (device 0x01) speak mm and mm/s. The
conversion to and from the SI units of everything ROS-facing happens here only
(`to_device_units`, `from_device_units`).

Silent in the document (assumed here, listed for docs/hardware.md): the data layout of MODEL
and HARDWARE_STATUS (carried as raw bytes); whether the 64-byte limit counts the COBS
overhead (taken as the raw packet, footer included).
"""

from __future__ import annotations

import struct
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from enum import IntEnum

import crcmod  # type: ignore[import-untyped]
from cobs import cobs  # type: ignore[import-untyped]

from uvms_hardware.errors import ProtocolError

#: Bytes of the footer PACKET_ID | DEVICE_ID | LENGTH | CRC.
FOOTER_BYTES = 4
#: Largest raw packet, footer included (bytes).
MAX_PACKET_BYTES = 64
#: Largest DATA of one packet (bytes).
MAX_DATA_BYTES = MAX_PACKET_BYTES - FOOTER_BYTES
#: Largest packet ids one REQUEST may ask for.
MAX_REQUEST_IDS = 10
#: Frame terminator.
TERMINATOR = b'\x00'
#: The jaws' length unit per metre (mm).
MM_PER_M = 1000.0

_crc8 = crcmod.mkCrcFun(0x14D, initCrc=0xFF, rev=True, xorOut=0xFF)


class PacketId(IntEnum):
    """Packet ids of the document."""

    MODE = 0x01
    VELOCITY = 0x02
    POSITION = 0x03
    CURRENT = 0x05
    INDEXED_POSITION = 0x0D
    RELATIVE_POSITION = 0x0E
    POSITION_LIMITS = 0x10
    VELOCITY_LIMITS = 0x11
    CURRENT_LIMITS = 0x12
    SAVE = 0x50
    REQUEST = 0x60
    MODEL = 0x62
    TEMPERATURE = 0x66
    HARDWARE_STATUS = 0x68
    VOLTAGE = 0x90
    HEARTBEAT_SET = 0x91
    HEARTBEAT_FREQUENCY = 0x92


class Mode(IntEnum):
    """Values of a MODE packet (uint8)."""

    STANDBY = 0x00
    DISABLE = 0x01
    POSITION = 0x02
    VELOCITY = 0x03
    CURRENT = 0x04
    PASSIVE = 0x26


class DeviceId(IntEnum):
    """Device ids of an Alpha 5: A jaws, B wrist rotate, C elbow, D shoulder, E base."""

    JAWS = 0x01
    WRIST = 0x02
    ELBOW = 0x03
    SHOULDER = 0x04
    BASE = 0x05
    ALL = 0xFF


#: The control packets: each switches the receiving device into its mode.
CONTROL_MODES = {PacketId.POSITION: Mode.POSITION, PacketId.VELOCITY: Mode.VELOCITY,
                 PacketId.CURRENT: Mode.CURRENT}
#: The packets carrying [max, min] floats.
LIMIT_PACKETS = (PacketId.POSITION_LIMITS, PacketId.VELOCITY_LIMITS, PacketId.CURRENT_LIMITS)
#: Packets whose floats are a length or a speed: mm and mm/s on the jaws.
_LENGTH_PACKETS = frozenset({PacketId.POSITION, PacketId.VELOCITY, PacketId.POSITION_LIMITS,
                             PacketId.VELOCITY_LIMITS, PacketId.INDEXED_POSITION,
                             PacketId.RELATIVE_POSITION})


@dataclass(frozen=True)
class Packet:
    """One decoded packet: its DATA bytes, packet id and device id."""

    device_id: int
    packet_id: int
    data: bytes

    def floats(self) -> tuple[float, ...]:
        """DATA as little-endian float32 values."""
        return data_floats(self.data)


def mode_of(value: int) -> Mode | None:
    """The Mode of a MODE packet's byte; None for a value the document does not list."""
    try:
        return Mode(value)
    except ValueError:
        return None


def crc8(data: bytes) -> int:
    """CRC-8 of the protocol over ``data`` (the raw packet less its CRC byte)."""
    return int(_crc8(bytes(data)))


def floats_data(values: Iterable[float]) -> bytes:
    """Little-endian float32 DATA of ``values``."""
    values = list(values)
    return struct.pack(f'<{len(values)}f', *values)


def data_floats(data: bytes) -> tuple[float, ...]:
    """Little-endian float32 values of DATA.

    Raises:
        ProtocolError: A length that is not a multiple of 4.
    """
    if len(data) % 4:
        raise ProtocolError(f'{len(data)} data bytes are no whole float32 values')
    return struct.unpack(f'<{len(data) // 4}f', data)


def encode_packet(device_id: int, packet_id: int, data: bytes = b'') -> bytes:
    """The frame of one packet: COBS(DATA | ids | LENGTH | CRC) then 0x00.

    Raises:
        ProtocolError: An id outside 0-255 or DATA longer than `MAX_DATA_BYTES`.
    """
    if not (0 <= device_id <= 0xFF and 0 <= packet_id <= 0xFF):
        raise ProtocolError(f'device id {device_id} / packet id {packet_id}: valid: 0-255')
    if len(data) > MAX_DATA_BYTES:
        raise ProtocolError(f'{len(data)} data bytes: at most {MAX_DATA_BYTES} fit a packet')
    body = bytes(data) + bytes((packet_id, device_id, len(data) + FOOTER_BYTES))
    return bytes(cobs.encode(body + bytes((crc8(body),)))) + TERMINATOR


def decode_frame(frame: bytes) -> Packet:
    """The packet of one frame (its trailing 0x00 optional).

    Raises:
        ProtocolError: A COBS error, a packet shorter than its footer or longer than 64
            bytes, a LENGTH that disagrees, or a CRC that does not match; the message says
            which.
    """
    encoded = frame[:-1] if frame.endswith(TERMINATOR) else frame
    try:
        raw = bytes(cobs.decode(encoded))
    except cobs.DecodeError as exc:
        raise ProtocolError(f'COBS: {exc}') from exc
    if not FOOTER_BYTES <= len(raw) <= MAX_PACKET_BYTES:
        raise ProtocolError(f'length: {len(raw)} bytes, valid: {FOOTER_BYTES}-{MAX_PACKET_BYTES}')
    if raw[-2] != len(raw):
        raise ProtocolError(f'length: LENGTH field {raw[-2]}, packet of {len(raw)} bytes')
    if crc8(raw[:-1]) != raw[-1]:
        raise ProtocolError(f'CRC: received {raw[-1]:#04x}, computed {crc8(raw[:-1]):#04x}')
    return Packet(device_id=raw[-3], packet_id=raw[-4], data=raw[:-FOOTER_BYTES])


def encode_mode(device_id: int, mode: Mode) -> bytes:
    """MODE packet: switch ``device_id`` to ``mode``."""
    return encode_packet(device_id, PacketId.MODE, bytes((int(mode),)))


def encode_floats(device_id: int, packet_id: int, values_si: Sequence[float]) -> bytes:
    """A float packet from SI values (m, m/s on the jaws; rad, rad/s, mA elsewhere)."""
    return encode_packet(device_id, packet_id,
                         floats_data(to_device_units(device_id, packet_id, values_si)))


def encode_velocity(device_id: int, velocity_si: float) -> bytes:
    """VELOCITY setpoint (rad/s; m/s for the jaws, sent as mm/s)."""
    return encode_floats(device_id, PacketId.VELOCITY, (velocity_si,))


def encode_position(device_id: int, position_si: float) -> bytes:
    """POSITION setpoint (rad; m for the jaws, sent as mm)."""
    return encode_floats(device_id, PacketId.POSITION, (position_si,))


def encode_current(device_id: int, current_ma: float) -> bytes:
    """CURRENT setpoint (mA)."""
    return encode_floats(device_id, PacketId.CURRENT, (current_ma,))


def encode_limits(device_id: int, packet_id: int, max_si: float, min_si: float) -> bytes:
    """POSITION_LIMITS / VELOCITY_LIMITS / CURRENT_LIMITS as [max, min] (SI values)."""
    if packet_id not in LIMIT_PACKETS:
        raise ProtocolError(f'packet id {packet_id:#04x} is no limits packet')
    return encode_floats(device_id, packet_id, (max_si, min_si))


def encode_request(device_id: int, packet_ids: Sequence[int]) -> bytes:
    """REQUEST of up to 10 packet ids from one device (no leading zeros, unlike RDML's).

    Raises:
        ProtocolError: No id, or more than `MAX_REQUEST_IDS`.
    """
    if not 0 < len(packet_ids) <= MAX_REQUEST_IDS:
        raise ProtocolError(f'a REQUEST asks for 1-{MAX_REQUEST_IDS} packet ids, '
                            f'got {len(packet_ids)}')
    return encode_packet(device_id, PacketId.REQUEST, bytes(int(p) for p in packet_ids))


def is_length_packet(device_id: int, packet_id: int) -> bool:
    """True where the device speaks mm or mm/s: the jaws' position and velocity packets."""
    return device_id == DeviceId.JAWS and packet_id in _LENGTH_PACKETS


def to_device_units(device_id: int, packet_id: int, values_si: Sequence[float]) -> list[float]:
    """SI values (m, m/s) as the device speaks them (mm, mm/s on the jaws; else unchanged)."""
    scale = MM_PER_M if is_length_packet(device_id, packet_id) else 1.0
    return [float(v) * scale for v in values_si]


def from_device_units(device_id: int, packet_id: int,
                      values_device: Sequence[float]) -> list[float]:
    """Device values as SI (mm, mm/s of the jaws to m, m/s; else unchanged)."""
    scale = MM_PER_M if is_length_packet(device_id, packet_id) else 1.0
    return [float(v) / scale for v in values_device]


def packet_values_si(packet: Packet) -> list[float]:
    """The float DATA of a packet in SI units (see `from_device_units`)."""
    return from_device_units(packet.device_id, packet.packet_id, packet.floats())


class FrameSplitter:
    """Splits a byte stream into packets; bad frames are dropped and counted, never raised.

    Feed it whatever the transport gives (datagrams, serial reads, single bytes); it yields
    every packet whose frame is complete. A run longer than any valid frame without a
    terminator is dropped up to the next 0x00 (counted as a length error).

    Attributes:
        packets: Packets decoded.
        crc_errors: Frames whose CRC did not match.
        length_errors: Frames too short or too long, or with a wrong LENGTH field.
        cobs_errors: Frames that were no valid COBS encoding.
        last_error: The message of the last bad frame ('' before the first).
    """

    #: Longest encoded frame before its terminator: COBS adds one byte per 254.
    MAX_ENCODED_BYTES = MAX_PACKET_BYTES + 1

    def __init__(self) -> None:
        self._buffer = bytearray()
        self._overflow = False
        self.packets = 0
        self.crc_errors = 0
        self.length_errors = 0
        self.cobs_errors = 0
        self.last_error = ''

    @property
    def bad_frames(self) -> int:
        """Every dropped frame: CRC, length and COBS errors."""
        return self.crc_errors + self.length_errors + self.cobs_errors

    def feed(self, chunk: bytes) -> list[Packet]:
        """The packets that ``chunk`` completes, in order (bad frames dropped and counted)."""
        packets: list[Packet] = []
        data = bytes(chunk)
        start = 0
        while True:  # by terminator (bytes.find), not byte by byte: 500 reads a second
            end = data.find(0, start)
            self._keep(data[start:] if end < 0 else data[start:end])
            if end < 0:
                return packets
            start = end + 1
            frame, overflow = bytes(self._buffer), self._overflow
            self._buffer.clear()
            self._overflow = False
            if overflow:
                self._count('length: frame longer than 64 bytes')
            elif frame:  # an empty frame (two terminators) is padding, not an error
                packet = self._decode(frame)
                if packet is not None:
                    packets.append(packet)

    def _keep(self, part: bytes) -> None:
        """Add ``part`` (no terminator in it) to the frame; what does not fit is dropped."""
        room = self.MAX_ENCODED_BYTES - len(self._buffer)
        if len(part) > room:
            self._buffer += part[:room]
            self._overflow = True
        else:
            self._buffer += part

    def _decode(self, frame: bytes) -> Packet | None:
        try:
            packet = decode_frame(frame)
        except ProtocolError as exc:
            self._count(str(exc))
            return None
        self.packets += 1
        return packet

    def _count(self, message: str) -> None:
        self.last_error = message
        if message.startswith('CRC'):
            self.crc_errors += 1
        elif message.startswith('COBS'):
            self.cobs_errors += 1
        else:
            self.length_errors += 1
