"""Reach System protocol codec: the document's vectors, independent round trips, bad frames."""

from __future__ import annotations

import struct

import pytest
from uvms_hardware.errors import ProtocolError

from uvms_hardware import reach_protocol as rp


def bitwise_crc8(data: bytes) -> int:
    """CRC-8 as the document states it, bit by bit: poly 0x4D reflected (0xB2), init 0, xor FF."""
    register = 0x00
    for byte in data:
        register ^= byte
        for _ in range(8):
            register = (register >> 1) ^ 0xB2 if register & 1 else register >> 1
    return register ^ 0xFF


def independent_decode(frame: bytes) -> tuple[bytes, int, int]:
    """(data, packet id, device id) of a frame by a COBS decode and CRC written here."""
    assert frame[-1] == 0 and 0 not in frame[:-1]
    encoded, raw, i = frame[:-1], bytearray(), 0
    while i < len(encoded):
        code = encoded[i]
        raw += encoded[i + 1:i + code]
        i += code
        if code < 0xFF and i < len(encoded):
            raw.append(0)
    assert raw[-2] == len(raw), 'LENGTH field'
    assert bitwise_crc8(bytes(raw[:-1])) == raw[-1], 'CRC'
    return bytes(raw[:-4]), raw[-4], raw[-3]


def test_crc_of_the_documents_vector() -> None:
    """CRC(FF 12 AD 23 56) = F3, by the codec and by the bitwise oracle."""
    assert rp.crc8(bytes.fromhex('FF12AD2356')) == 0xF3
    assert bitwise_crc8(bytes.fromhex('FF12AD2356')) == 0xF3


def test_request_of_position_encodes_as_the_document_shows() -> None:
    """A REQUEST of POSITION to device 0x01 is 06 03 60 01 05 52 00."""
    frame = rp.encode_request(0x01, [rp.PacketId.POSITION])
    assert frame == bytes.fromhex('06036001055200')


def test_document_frame_decodes_to_its_fields() -> None:
    """09 01 02 03 04 01 FF 08 5D 00 is data 01 02 03 04, packet 0x01, device 0xFF."""
    packet = rp.decode_frame(bytes.fromhex('0901020304' '01FF085D00'))
    assert packet == rp.Packet(device_id=0xFF, packet_id=0x01, data=bytes.fromhex('01020304'))


def test_document_position_example_is_4_123_rad_to_device_1() -> None:
    """09 9E EF 83 40 03 01 08 B8 00 is POSITION 4.123 to device 0x01, both ways."""
    frame = bytes.fromhex('099EEF834003' '0108B800')
    packet = rp.decode_frame(frame)
    assert (packet.device_id, packet.packet_id) == (0x01, rp.PacketId.POSITION)
    assert packet.floats()[0] == pytest.approx(4.123, abs=1e-6)
    raw = rp.encode_packet(0x01, rp.PacketId.POSITION, struct.pack('<f', 4.123))
    assert raw == frame


@pytest.mark.parametrize('frame', [
    rp.encode_mode(0x05, rp.Mode.STANDBY),
    rp.encode_mode(0x02, rp.Mode.PASSIVE),
    rp.encode_velocity(0x03, -0.25),
    rp.encode_velocity(0x01, 0.0),
    rp.encode_position(0x04, 1.5),
    rp.encode_current(0x02, -123.5),
    rp.encode_request(0x05, [rp.PacketId.POSITION, rp.PacketId.VELOCITY]),
    rp.encode_request(0x03, [rp.PacketId.MODEL]),
    rp.encode_request(0x02, [rp.PacketId.POSITION_LIMITS, rp.PacketId.VELOCITY_LIMITS,
                             rp.PacketId.CURRENT_LIMITS]),
    rp.encode_limits(0x04, rp.PacketId.POSITION_LIMITS, 3.49, -3.49),
    rp.encode_limits(0x05, rp.PacketId.CURRENT_LIMITS, 600.0, -600.0),
    rp.encode_packet(0x01, rp.PacketId.MODEL, bytes(range(1, 9)) + b'\x00\x00'),
])
def test_every_bridge_packet_round_trips_through_an_independent_decoder(frame: bytes) -> None:
    """What the codec encodes, a decoder written here reads back, and so does the codec."""
    data, packet_id, device_id = independent_decode(frame)
    assert rp.decode_frame(frame) == rp.Packet(device_id, packet_id, data)


def test_floats_round_trip_in_si_units() -> None:
    """A velocity of -0.25 rad/s on the elbow is -0.25 on the wire and back."""
    data, _, _ = independent_decode(rp.encode_velocity(0x03, -0.25))
    assert struct.unpack('<f', data)[0] == -0.25


def test_jaws_speak_millimetres() -> None:
    """0.01 m to the jaws is 10 mm on the wire, and 10 mm back is 0.01 m."""
    data, _, _ = independent_decode(rp.encode_position(rp.DeviceId.JAWS, 0.01))
    assert struct.unpack('<f', data)[0] == pytest.approx(10.0)
    packet = rp.decode_frame(rp.encode_packet(0x01, rp.PacketId.VELOCITY, struct.pack('<f', 5)))
    assert rp.packet_values_si(packet) == pytest.approx([0.005])


def test_joint_positions_are_not_scaled() -> None:
    """A joint's radians and a current's mA pass unchanged."""
    assert rp.to_device_units(0x02, rp.PacketId.POSITION, [1.0]) == [1.0]
    assert rp.to_device_units(0x01, rp.PacketId.CURRENT, [100.0]) == [100.0]


def test_request_refuses_more_than_ten_ids() -> None:
    """A REQUEST carries 1 to 10 ids."""
    with pytest.raises(ProtocolError, match='1-10'):
        rp.encode_request(0x01, [rp.PacketId.POSITION] * 11)


def test_packet_over_64_bytes_is_refused() -> None:
    """61 data bytes do not fit a 64-byte packet."""
    with pytest.raises(ProtocolError, match='at most 60'):
        rp.encode_packet(0x01, 0x02, bytes(61))


def test_wrong_crc_raises_naming_the_crc() -> None:
    """One flipped CRC bit is a ProtocolError about the CRC."""
    frame = bytearray(rp.encode_velocity(0x03, 0.1))
    frame[-2] ^= 0x01
    with pytest.raises(ProtocolError, match='CRC'):
        rp.decode_frame(bytes(frame))


def test_splitter_yields_packets_from_arbitrary_chunks() -> None:
    """Frames cut at every byte still give every packet, in order."""
    frames = [rp.encode_velocity(d, 0.1 * d) for d in (2, 3, 4, 5)]
    stream = b''.join(frames)
    splitter = rp.FrameSplitter()
    packets = [p for i in range(len(stream)) for p in splitter.feed(stream[i:i + 1])]
    assert [p.device_id for p in packets] == [2, 3, 4, 5]
    assert splitter.bad_frames == 0


def test_splitter_survives_and_counts_bad_frames() -> None:
    """A CRC error, a short frame, a COBS error and an overlong run are counted, not raised."""
    good = rp.encode_velocity(0x02, 0.2)
    bad_crc = bytearray(good)
    bad_crc[3] ^= 0xFF
    short = bytes.fromhex('03010200')  # a 2-byte packet, shorter than its footer
    bad_cobs = bytes.fromhex('0901020300')  # the code byte promises more than there is
    overlong = bytes([0x11] * 100) + b'\x00'
    splitter = rp.FrameSplitter()
    stream = bytes(bad_crc) + short + bad_cobs + overlong + good
    packets = list(splitter.feed(stream))
    assert [p.device_id for p in packets] == [0x02]
    assert (splitter.crc_errors, splitter.length_errors, splitter.cobs_errors) == (1, 2, 1)
    assert splitter.bad_frames == 4 and splitter.packets == 1


def test_splitter_ignores_empty_frames() -> None:
    """Consecutive terminators are padding, not errors."""
    splitter = rp.FrameSplitter()
    assert list(splitter.feed(b'\x00\x00\x00')) == []
    assert splitter.bad_frames == 0
