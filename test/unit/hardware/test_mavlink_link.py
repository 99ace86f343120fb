"""Tests of uvms_hardware.ardusub_link against the ArduSub twin (MAVLink on 127.0.0.1, no ROS)."""

from __future__ import annotations

import socket
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from pymavlink import mavutil
from uvms_hardware.ardusub_link import ArduSubLink, LinkSettings
from uvms_hardware.errors import DeviceCheckError
from uvms_hardware.t200_curve import robot_curve
from uvms_twins.ardusub_twin import ArduSubTwin

MAV = mavutil.mavlink
ALL = (1, 2, 3, 4, 5, 6, 7, 8)


def _link(url: str, channels: tuple[int, ...] = ALL, gcs_id: int = 255) -> ArduSubLink:
    link = ArduSubLink(LinkSettings(url, channels, gcs_system_id=gcs_id, reply_timeout_s=0.3,
                                    retries=2), robot_curve())
    link.open()
    return link


@pytest.fixture(autouse=True)
def journal_dir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """Journals of original values go to the test's folder, never the user's."""
    monkeypatch.setenv('UVMS_JOURNAL_DIR', str(tmp_path))
    return tmp_path


@pytest.fixture
def twin() -> Iterator[ArduSubTwin]:
    """An ArduSub twin on a free loopback port."""
    with ArduSubTwin() as running:
        yield running


@pytest.fixture
def link(twin: ArduSubTwin) -> Iterator[ArduSubLink]:
    """A link that has found the twin."""
    connected = _link(twin.url)
    connected.wait_vehicle(3.0)
    yield connected
    connected.close()


def _free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.bind(('127.0.0.1', 0))
        return int(sock.getsockname()[1])


def test_vehicle_found_as_ardupilot_submarine(link: ArduSubLink) -> None:
    """The twin's HEARTBEAT identifies ArduSub; its system id becomes the target."""
    assert link.vehicle.system_id == 1 and link.vehicle.custom_mode == 19
    assert link.link_age_s() < 1.5


def test_a_vehicle_that_never_answers_is_refused() -> None:
    """No HEARTBEAT within the timeout: DeviceCheckError naming the wait."""
    link = _link(f'udpout:127.0.0.1:{_free_udp_port()}')
    with pytest.raises(DeviceCheckError, match=r'no vehicle HEARTBEAT within 0\.5 s'):
        link.wait_vehicle(0.5)
    link.close()


def test_a_vehicle_that_is_not_ardusub_is_refused() -> None:
    """A quadrotor's HEARTBEAT is named, not taken for ArduSub."""
    copter: Any = mavutil.mavlink_connection('udpin:127.0.0.1:0', source_system=7)
    port = copter.port.getsockname()[1]
    link = _link(f'udpout:127.0.0.1:{port}')
    assert copter.recv_match(type='HEARTBEAT', blocking=True, timeout=2.0) is not None
    for _ in range(3):
        copter.mav.heartbeat_send(MAV.MAV_TYPE_QUADROTOR, MAV.MAV_AUTOPILOT_ARDUPILOTMEGA, 0, 0, 0)
    with pytest.raises(DeviceCheckError, match='system 7 type 2 autopilot 3'):
        link.wait_vehicle(0.5)
    link.close()
    copter.close()


def test_gcs_id_mismatch_is_refused_naming_both_numbers(link: ArduSubLink) -> None:
    """MAV_GCS_SYSID 255 against our 254: the message names 255 and 254."""
    mismatched = _link(link.settings.url, gcs_id=254)
    mismatched.wait_vehicle(3.0)
    expected = r'GCS system id 255 \(MAV_GCS_SYSID\), ours is 254'
    with pytest.raises(DeviceCheckError, match=expected):
        mismatched.check_gcs_id()
    mismatched.close()
    assert link.check_gcs_id() == ('MAV_GCS_SYSID', 255)


def test_older_firmware_gcs_id_is_read_from_sysid_mygcs() -> None:
    """Without MAV_GCS_SYSID the check falls back to SYSID_MYGCS."""
    with ArduSubTwin(gcs_param='SYSID_MYGCS') as old:
        link = _link(old.url)
        link.wait_vehicle(3.0)
        assert link.check_gcs_id() == ('SYSID_MYGCS', 255)
        link.close()


def test_unprotected_failsafes_are_warned() -> None:
    """FS_GCS_ENABLE 0, FS_PILOT_INPUT 0 and RC_OVERRIDE_TIME -1 each give a warning."""
    values = {'FS_GCS_ENABLE': 0.0, 'FS_PILOT_INPUT': 0.0, 'RC_OVERRIDE_TIME': -1.0}
    with ArduSubTwin(parameters=values) as twin:
        link = _link(twin.url)
        link.wait_vehicle(3.0)
        text = '\n'.join(link.failsafe_warnings())
        link.close()
    for name in values:
        assert f'{name} = ' in text


def test_passthrough_then_restore_puts_every_function_back(
        twin: ArduSubTwin, link: ArduSubLink) -> None:
    """Outputs go to RCIN1..8 (51..58) while active and back to Motor1..8 (33..40)."""
    link.enable_passthrough()
    link.arm(True)
    assert twin.armed
    assert [twin.param(f'SERVO{n}_FUNCTION') for n in ALL] == [50.0 + n for n in ALL]
    assert link.restore() == []
    assert [twin.param(f'SERVO{n}_FUNCTION') for n in ALL] == [32.0 + n for n in ALL]
    assert not twin.armed and link.changed_functions == {}


def test_a_channel_that_does_not_take_passthrough_is_named(twin: ArduSubTwin) -> None:
    """A vehicle that keeps SERVO3_FUNCTION: activation refused naming channel 3."""
    original = twin._handle

    def drop_servo3(msg: Any, now_s: float) -> None:
        if not (msg.get_type() == 'PARAM_SET' and msg.param_id == 'SERVO3_FUNCTION'):
            original(msg, now_s)

    twin._handle = drop_servo3  # type: ignore[method-assign]
    link = _link(twin.url)
    link.wait_vehicle(3.0)
    with pytest.raises(DeviceCheckError, match='channel 3 is not in passthrough'):
        link.enable_passthrough()
    assert link.restore() == []  # outputs 1 and 2 were changed: they go back
    assert twin.param('SERVO1_FUNCTION') == 33.0
    link.close()


def test_override_frames_decode_with_our_ids_and_channel_semantics(
        twin: ArduSubTwin, link: ArduSubLink) -> None:
    """Decoded by pymavlink: our GCS ids, the target, PWM 1100-1900, 65535 / 0 elsewhere."""
    six = LinkSettings(link.settings.url, (1, 2, 3, 4, 5, 6))
    link.settings = six
    link.enable_passthrough()
    link.send_override(link.pwm_for([100.0, -100.0, 0.0, 5.0, -5.0, 1.0]))
    time.sleep(0.2)
    record = twin.overrides()[-1]
    assert (record.src_system, record.src_component) == (255, MAV.MAV_COMP_ID_MISSIONPLANNER)
    assert (record.target_system, record.target_component) == (1, 1) and record.obeyed
    assert record.channels[:6] == (1900, 1100, 1500, record.channels[3], record.channels[4],
                                   record.channels[5])
    assert all(1100 <= pwm <= 1900 for pwm in record.channels[:6])
    assert record.channels[6:8] == (65535, 65535) and record.channels[8:] == (0,) * 10
    assert twin.servo_outputs_us()[:3] == [1900, 1100, 1500]
    link.restore()


def test_direction_is_applied_once_per_thruster(link: ArduSubLink) -> None:
    """A reversed thruster gets the mirror pulse of the same thrust."""
    link.settings = LinkSettings(link.settings.url, (1, 2), (1, -1))
    pwm = link.pwm_for([10.0, 10.0])
    assert pwm[1] > 1528 and pwm[2] < 1472


def test_a_silent_vehicle_is_restored_without_waiting(twin: ArduSubTwin) -> None:
    """The vehicle stops answering while active: restore sends everything blind, at once."""
    link = ArduSubLink(LinkSettings(twin.url, ALL, silent_after_s=0.3), robot_curve())
    link.open()
    link.wait_vehicle(3.0)
    link.enable_passthrough()
    twin.silent = True
    time.sleep(0.5)
    start = time.monotonic()
    problems = link.restore()
    assert time.monotonic() - start < 0.2
    assert len(problems) == 1 and 'without confirmation' in problems[0]
    link.close()


def _impostor(link: ArduSubLink, system_id: int, component_id: int) -> Any:
    """A MAVLink peer whose messages reach our link, as a router forwards others' traffic."""
    port = link.conn.port.getsockname()[1]
    return mavutil.mavlink_connection(f'udpout:127.0.0.1:{port}', source_system=system_id,
                                      source_component=component_id, dialect='ardupilotmega')


def _deaf_to(twin: ArduSubTwin, kind: str) -> None:
    """The twin stops answering one kind of message (so that only the impostor answers)."""
    original = twin._handle

    def handle(msg: Any, now_s: float) -> None:
        if msg.get_type() != kind:
            original(msg, now_s)

    twin._handle = handle  # type: ignore[method-assign]


@pytest.mark.parametrize('source', [(1, 100), (7, 1)])
def test_a_param_value_from_anyone_but_the_vehicle_is_not_taken(
        twin: ArduSubTwin, link: ArduSubLink, source: tuple[int, int]) -> None:
    """PARAM_VALUE from another component or system (a camera, a second vehicle): ignored."""
    _deaf_to(twin, 'PARAM_REQUEST_READ')
    other = _impostor(link, *source)
    for _ in range(3):
        other.mav.param_value_send(b'MAV_GCS_SYSID', 254.0, MAV.MAV_PARAM_TYPE_INT16, 1, 0)
    assert link.read_param('MAV_GCS_SYSID') is None
    other.close()


def test_a_command_ack_addressed_to_another_ground_station_is_not_ours(
        twin: ArduSubTwin, link: ArduSubLink) -> None:
    """The vehicle's ACK of another GCS's arm (target 254) does not answer ours; ours does."""
    _deaf_to(twin, 'COMMAND_LONG')
    vehicle = _impostor(link, 1, 1)  # the vehicle's own ids, its answer to someone else
    arm = MAV.MAV_CMD_COMPONENT_ARM_DISARM
    for _ in range(3):
        vehicle.mav.command_ack_send(arm, MAV.MAV_RESULT_ACCEPTED, 0, 0, 254, 190)
    assert link.command(arm, 1.0) is None
    vehicle.mav.command_ack_send(arm, MAV.MAV_RESULT_ACCEPTED, 0, 0, 255,
                                 MAV.MAV_COMP_ID_MISSIONPLANNER)
    assert link.command(arm, 1.0) == MAV.MAV_RESULT_ACCEPTED
    vehicle.close()


def test_the_twin_addresses_its_command_acks_to_the_sender(
        twin: ArduSubTwin, link: ArduSubLink) -> None:
    """As GCS_Common.cpp does: target system and component of the ACK are the command's source."""
    link.arm(True)
    assert twin.armed


def test_a_second_ground_station_with_our_system_id_is_refused(link: ArduSubLink) -> None:
    """QGroundControl's default id 255 beside us: refused, its component named."""
    qgc = _impostor(link, 255, 191)
    for _ in range(2):
        qgc.mav.heartbeat_send(MAV.MAV_TYPE_GCS, MAV.MAV_AUTOPILOT_INVALID, 0, 0, 0)
    with pytest.raises(DeviceCheckError, match=r'our system id 255 .*component 191'):
        link.check_other_gcs()
    qgc.close()


def test_a_second_ground_station_with_another_id_is_a_warning(link: ArduSubLink) -> None:
    """A GCS of system 254: named in a warning (the vehicle ignores its overrides)."""
    other = _impostor(link, 254, 190)
    for _ in range(2):
        other.mav.heartbeat_send(MAV.MAV_TYPE_GCS, MAV.MAV_AUTOPILOT_INVALID, 0, 0, 0)
    warnings = link.check_other_gcs()
    assert len(warnings) == 1 and 'system 254 component 190' in warnings[0]
    other.close()
