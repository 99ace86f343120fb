"""The Alpha 5 twin behaves as the protocol document describes, per device."""

from __future__ import annotations

import socket

import pytest
from uvms_hardware.hardware_config import load_alpha5
from uvms_hardware.reach_protocol import DeviceId, Mode, PacketId
from uvms_twins.alpha5_twin import Alpha5Twin, current_to_torque_n_m

from uvms_hardware import reach_protocol as rp


@pytest.fixture
def twin() -> Alpha5Twin:
    """A twin of bluerov2_alpha5 with its jaw, not serving (packets handled directly)."""
    return Alpha5Twin(load_alpha5('bluerov2_alpha5', jaw_joint='jaw'), port=0)


def send(twin: Alpha5Twin, frame: bytes) -> list[rp.Packet]:
    """Handle one frame; the packets of the answer."""
    reply = twin.handle(rp.decode_frame(frame))
    return list(rp.FrameSplitter().feed(reply))


def test_devices_start_in_standby(twin: Alpha5Twin) -> None:
    """Every device answers MODE Standby before any command."""
    answer = send(twin, rp.encode_request(0x03, [PacketId.MODE]))
    assert answer[0].data == bytes((Mode.STANDBY,))


def test_control_packet_switches_the_mode(twin: Alpha5Twin) -> None:
    """A VELOCITY packet puts the elbow into Velocity mode with its setpoint."""
    send(twin, rp.encode_velocity(0x03, 0.2))
    assert twin.joint_commands()['joint_3'] == (Mode.VELOCITY, pytest.approx(0.2))


@pytest.mark.parametrize('mode', [Mode.DISABLE, Mode.PASSIVE])
def test_disable_and_passive_ignore_control_packets(twin: Alpha5Twin, mode: Mode) -> None:
    """In Disable or Passive a CURRENT packet changes nothing."""
    send(twin, rp.encode_mode(0x04, mode))
    send(twin, rp.encode_current(0x04, 100.0))
    assert twin.joint_commands()['joint_2'] == (mode, 0.0)


def test_velocity_and_current_are_clamped(twin: Alpha5Twin) -> None:
    """2 rad/s is clamped at 0.5; -900 mA at -600 (device E)."""
    send(twin, rp.encode_velocity(0x02, 2.0))
    send(twin, rp.encode_current(0x05, -900.0))
    commands = twin.joint_commands()
    assert commands['joint_4'] == (Mode.VELOCITY, 0.5)
    assert commands['joint_1'] == (Mode.CURRENT, -600.0)


def test_out_of_limit_position_is_ignored(twin: Alpha5Twin) -> None:
    """POSITION 4 rad on the elbow (0..3.22) is ignored; 1 rad is taken."""
    send(twin, rp.encode_position(0x03, 4.0))
    assert twin.joint_commands()['joint_3'] == (Mode.STANDBY, 0.0)
    send(twin, rp.encode_position(0x03, 1.0))
    assert twin.joint_commands()['joint_3'] == (Mode.POSITION, 1.0)


def test_request_is_answered_by_the_named_device_in_si_on_the_wire_in_mm(
        twin: Alpha5Twin) -> None:
    """The jaw at 0.01 m answers 10 mm; the codec reads 0.01 m back."""
    twin.set_joint_state([0.1, 0.2, 0.3, 0.4, 0.01], [0.0, 0.0, 0.0, 0.0, -0.002])
    answer = send(twin, rp.encode_request(DeviceId.JAWS, [PacketId.POSITION, PacketId.VELOCITY]))
    assert [p.packet_id for p in answer] == [PacketId.POSITION, PacketId.VELOCITY]
    assert answer[0].floats()[0] == pytest.approx(10.0)
    assert rp.packet_values_si(answer[0]) == pytest.approx([0.01])
    assert rp.packet_values_si(answer[1]) == pytest.approx([-0.002])


def test_broadcast_request_is_answered_by_no_device(twin: Alpha5Twin) -> None:
    """A REQUEST to 0xFF would collide on RS-485: no device answers."""
    assert send(twin, rp.encode_request(DeviceId.ALL, [PacketId.POSITION])) == []


def test_broadcast_mode_reaches_every_device(twin: Alpha5Twin) -> None:
    """MODE Disable to 0xFF disables all five devices."""
    send(twin, rp.encode_mode(DeviceId.ALL, Mode.DISABLE))
    assert {mode for mode, _ in twin.joint_commands().values()} == {Mode.DISABLE}


def test_limits_answered_as_max_min_from_the_urdf(twin: Alpha5Twin) -> None:
    """joint_2's POSITION_LIMITS are [3.49, -3.49]; the jaw's [0.015 m, 0] as [15, 0] mm."""
    answer = send(twin, rp.encode_request(0x04, [PacketId.POSITION_LIMITS]))
    assert answer[0].floats() == pytest.approx((3.49, -3.49))
    jaw = send(twin, rp.encode_request(0x01, [PacketId.POSITION_LIMITS]))
    assert jaw[0].floats() == pytest.approx((15.0, 0.0))


def test_silent_device_answers_nothing(twin: Alpha5Twin) -> None:
    """A silent device does not answer MODEL."""
    twin.set_silent(0x02)
    assert send(twin, rp.encode_request(0x02, [PacketId.MODEL])) == []


def test_twin_keeps_the_last_command_when_the_host_goes_silent(twin: Alpha5Twin) -> None:
    """Unknown from the documents: the twin keeps the last current (the unsafe reading)."""
    send(twin, rp.encode_current(0x05, 100.0))
    assert twin.joint_commands()['joint_1'] == (Mode.CURRENT, 100.0)


def test_current_command_becomes_joint_torque(twin: Alpha5Twin) -> None:
    """100 mA on joint_1 is 0.1 A * 0.0134 * 1754.4 * 0.86 N m."""
    send(twin, rp.encode_current(0x05, 100.0))
    torques = twin.joint_torques_n_m()
    assert torques['joint_1'] == pytest.approx(0.1 * 0.0134 * 1754.4 * 0.86)
    assert torques['joint_2'] is None
    drive = load_alpha5('bluerov2_alpha5').joints[3]
    assert current_to_torque_n_m(drive, 1000.0) == pytest.approx(0.0271 * 340.4 * 0.77)


def test_serves_udp_on_loopback(twin: Alpha5Twin) -> None:
    """Over UDP on 127.0.0.1 a MODEL request is answered with the model data."""
    with twin, socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.settimeout(2.0)
        sock.sendto(rp.encode_request(0x05, [PacketId.MODEL]), ('127.0.0.1', twin.port))
        reply, _ = sock.recvfrom(4096)
    (packet,) = rp.FrameSplitter().feed(reply)
    assert (packet.device_id, packet.packet_id, packet.data) == (5, PacketId.MODEL, b'alpha5')


def test_mode_standby_after_velocity_and_unknown_mode_ignored(twin: Alpha5Twin) -> None:
    """MODE Standby (value 0) is taken; a mode value the document does not list is ignored."""
    send(twin, rp.encode_velocity(0x05, 0.1))
    send(twin, rp.encode_mode(0x05, Mode.STANDBY))
    assert twin.joint_commands()['joint_1'][0] == Mode.STANDBY
    send(twin, rp.encode_packet(0x05, PacketId.MODE, b'\x77'))
    assert twin.joint_commands()['joint_1'][0] == Mode.STANDBY


def test_dropped_datagrams_reach_no_device() -> None:
    """drop_first_datagrams=2: two MODE Disable datagrams are lost, the third is taken."""
    arm = load_alpha5('bluerov2_alpha5')
    with Alpha5Twin(arm, port=0, drop_first_datagrams=2) as twin, socket.socket(
            socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.settimeout(2.0)
        for _ in range(3):
            sock.sendto(rp.encode_mode(0x05, Mode.DISABLE) + rp.encode_request(
                0x05, [PacketId.MODE]), ('127.0.0.1', twin.port))
        reply, _ = sock.recvfrom(4096)
        assert twin.dropped == 2 and len(twin.received(0x05)) == 2  # MODE and REQUEST once
    (packet,) = rp.FrameSplitter().feed(reply)
    assert packet.data == bytes((Mode.DISABLE,))
