"""The twins in the simulator's process: the plant's state by call reaches the bridges.

``uvms_twins.simulator_with_twins.InProcessTwins`` is what the simulator calls at each state
(``observe``), at each navigation reading (``reading``) and for its command (``command``).
Each test talks to the twins as the bridges do, on their sockets (pymavlink for ArduSub,
Reach frames over UDP, RDT over UDP, the DVL's TCP JSON), on ports of their own.
"""

from __future__ import annotations

import json
import math
import os
import socket
import time
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import pytest
from pymavlink import mavutil
from uvms_hardware.hardware_config import hardware_section, load_alpha5
from uvms_hardware.netft_core import DEFAULT_ROT_LINK_FROM_SENSOR
from uvms_hardware.reach_protocol import Mode, PacketId
from uvms_model.nav_sensors import DepthReading, DvlReading, ImuReading
from uvms_sim.conversions import quaternion_from_rpy
from uvms_sim.plant import Observation
from uvms_twins.alpha5_twin import current_to_torque_n_m
from uvms_twins.simulator_with_twins import InProcessTwins
from uvms_twins.twin_stand import GRAVITY_M_S2, TwinStand

from uvms_hardware import rdt_protocol as rdt
from uvms_hardware import reach_protocol as rp

ROBOT = 'bluerov2_alpha5'
#: The plant's joints in an order other than the arm's, so that a mix-up shows.
PLANT_JOINTS = ('joint_4', 'joint_2', 'joint_3', 'joint_1')
PORTS = {'ardusub_bridge.connection': 'udpout:127.0.0.1:24551',
         'dvl_bridge.connection': '127.0.0.1:26171',
         'alpha5_bridge.connection': 'udp:127.0.0.1:26789',
         'netft_bridge.connection': '127.0.0.1:29152'}
MAV = mavutil.mavlink


def wait(condition: Callable[[], bool], timeout_s: float, what: str) -> None:
    """Poll until condition() or fail naming what."""
    end = time.monotonic() + timeout_s
    while not condition():
        assert time.monotonic() < end, f'timed out waiting for {what}'
        time.sleep(0.005)


def observation(t_ns: int, q_joints: list[float], w_joints: list[float],
                force: list[float], torque: list[float]) -> Observation:
    """A plant state with these joints (PLANT_JOINTS' order) and wrist wrench."""
    q = np.array([0.0] * 6 + q_joints)
    w = np.array([0.0] * 6 + w_joints)
    return Observation(t_ns, q, w, np.zeros(4), {}, None,  # type: ignore[arg-type]
                       np.array(force), np.array(torque))


@pytest.fixture
def twins() -> Iterator[InProcessTwins]:
    """The stand of bluerov2_alpha5 as the simulator's plant side, plant time from its states."""
    holder: list[InProcessTwins] = []
    stand = TwinStand(ROBOT, PORTS, lambda: holder[0].plant_s(), lambda line: None)
    holder.append(InProcessTwins(stand, PLANT_JOINTS))
    try:
        yield holder[0]
    finally:
        stand.stop()


def imu(t_ns: int, rpy: tuple[float, float, float] = (0.1, -0.2, 1.0)) -> ImuReading:
    """An IMU reading at rest with this attitude."""
    return ImuReading(t_ns, np.array([0.01, 0.02, 0.03]), np.array([0.0, 0.0, -9.81]),
                      np.array(rpy), np.full(3, 0.01))


def serve(twins: InProcessTwins) -> None:
    """Give the twins a first state: joints, wrench, IMU, depth."""
    twins.observe(observation(2_000_000, [0.4, 0.2, 0.3, 0.1], [0.04, 0.02, 0.03, 0.01],
                              [1.0, -2.0, 3.0], [0.1, 0.2, -0.3]))
    twins.reading(imu(2_000_000))
    twins.reading(DepthReading(2_000_000, 1.25, 0.01))


def gcs(twins: InProcessTwins) -> Any:
    """A pymavlink GCS (system 255) heard by the ArduSub twin."""
    os.environ['MAVLINK20'] = '1'
    conn = mavutil.mavlink_connection(twins.stand.ardusub.url, source_system=255,
                                      source_component=190, dialect='ardupilotmega')
    conn.mav.heartbeat_send(MAV.MAV_TYPE_GCS, MAV.MAV_AUTOPILOT_INVALID, 0, 0, 0)
    return conn


def test_the_twins_serve_once_the_plant_gave_joints_and_imu(twins: InProcessTwins) -> None:
    """Joint states alone are not a state of the devices: the IMU's makes them serve."""
    twins.observe(observation(0, [0.0] * 4, [0.0] * 4, [0.0] * 3, [0.0] * 3))
    assert not twins.stand.serving
    twins.reading(imu(0))
    assert twins.stand.serving


def test_the_arm_answers_the_plants_joints_by_name(twins: InProcessTwins) -> None:
    """joint_2's device answers joint_2's position and velocity, whatever the plant's order."""
    serve(twins)
    device = {d.joint_name: d.device_id for d in load_alpha5(ROBOT).drives}
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.settimeout(2.0)
        port = int(PORTS['alpha5_bridge.connection'].rsplit(':', 1)[1])
        sock.sendto(rp.encode_request(device['joint_2'], [PacketId.POSITION, PacketId.VELOCITY]),
                    ('127.0.0.1', port))
        reply, _ = sock.recvfrom(4096)
    position, velocity = rp.FrameSplitter().feed(reply)
    assert rp.packet_values_si(position) == pytest.approx([0.2])
    assert rp.packet_values_si(velocity) == pytest.approx([0.02])


def test_the_netft_streams_the_plants_wrench_in_the_sensors_axes(twins: InProcessTwins) -> None:
    """RDT records carry the wrist's wrench rotated from ft_sensor_link into the sensor."""
    serve(twins)
    rot = np.array(DEFAULT_ROT_LINK_FROM_SENSOR).reshape(3, 3).T
    expected = np.concatenate([rot @ [1.0, -2.0, 3.0], rot @ [0.1, 0.2, -0.3]]) * 1e6
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.settimeout(2.0)
        port = int(PORTS['netft_bridge.connection'].rsplit(':', 1)[1])
        sock.sendto(rdt.encode_request(rdt.COMMAND_START_REALTIME), ('127.0.0.1', port))
        record = rdt.decode_record(sock.recvfrom(64)[0])
    np.testing.assert_allclose(record.counts, expected, atol=1.0)


def test_ardusub_reports_the_imus_attitude_and_the_depths_pressure(
        twins: InProcessTwins) -> None:
    """ATTITUDE_QUATERNION is the IMU reading's; SCALED_PRESSURE2 the depth's pressure."""
    serve(twins)
    conn = gcs(twins)
    try:
        for message in (MAV.MAVLINK_MSG_ID_ATTITUDE_QUATERNION,
                        MAV.MAVLINK_MSG_ID_SCALED_PRESSURE2):
            conn.mav.command_long_send(1, 1, MAV.MAV_CMD_SET_MESSAGE_INTERVAL, 0, message,
                                       20_000, 0, 0, 0, 0, 0)
        attitude = conn.recv_match(type='ATTITUDE_QUATERNION', blocking=True, timeout=3.0)
        pressure = conn.recv_match(type='SCALED_PRESSURE2', blocking=True, timeout=3.0)
    finally:
        conn.close()
    x, y, z, w = quaternion_from_rpy(0.1, -0.2, 1.0)
    assert (attitude.q1, attitude.q2, attitude.q3, attitude.q4) == pytest.approx(
        (w, x, y, z), abs=1e-6)
    _, section = hardware_section(ROBOT, 'ardusub')
    depth = section['depth']
    expected_pa = (depth['surface_pressure_pa']
                   + depth['water_density_kg_m3'] * GRAVITY_M_S2 * 1.25)
    assert pressure.press_abs * 100.0 == pytest.approx(expected_pa, abs=1.0)


def test_the_dvl_sends_each_valid_reading_with_its_time_and_altitude(
        twins: InProcessTwins) -> None:
    """A valid reading: one velocity report at once, time_of_validity the plant's time."""
    serve(twins)
    port = int(PORTS['dvl_bridge.connection'].rsplit(':', 1)[1])
    with socket.create_connection(('127.0.0.1', port), timeout=2.0) as sock:
        wait(lambda: twins.stand.dvl.client_count() > 0, 2.0, 'the DVL client')
        twins.reading(DvlReading(3_000_000_000, True, np.array([0.3, -0.1, 0.05]), 0.02, 1.4))
        stream = sock.makefile('rb')
        report: dict[str, Any] = {}
        while report.get('time_of_validity') != 3_000_000:  # the idle reports before it
            report = json.loads(stream.readline())
    assert report['type'] == 'velocity' and report['velocity_valid']
    assert (report['vx'], report['vy'], report['vz']) == pytest.approx((0.3, -0.1, 0.05))
    assert report['fom'] == pytest.approx(0.02)
    assert report['altitude'] == pytest.approx(1.4)


def test_no_command_until_the_bridges_drive_then_torques_in_the_plants_order(
        twins: InProcessTwins) -> None:
    """Armed, overridden and every joint driven: thrusts and torques, joint_3's where it is."""
    serve(twins)
    assert twins.command(2_000_000) is None
    conn = gcs(twins)
    try:
        conn.mav.command_long_send(1, 1, MAV.MAV_CMD_COMPONENT_ARM_DISARM, 0, 1, 0, 0, 0, 0, 0,
                                   0)
        wait(lambda: twins.stand.ardusub.armed, 3.0, 'armed')
        conn.mav.rc_channels_override_send(1, 1, *[1500] * 8, *[0] * 10)
        wait(lambda: bool(twins.stand.ardusub.overrides()), 3.0, 'the override')
    finally:
        conn.close()
    assert twins.command(2_000_000) is None  # the arm is not driven yet
    arm = twins.stand.arm
    drives = {d.joint_name: d for d in load_alpha5(ROBOT).drives}
    for joint, drive in drives.items():
        frame = (rp.encode_current(drive.device_id, 300.0) if joint == 'joint_3'
                 else rp.encode_velocity(drive.device_id, 0.0))
        arm.handle(rp.decode_frame(frame))
    assert arm.joint_commands()['joint_3'][0] == Mode.CURRENT
    command = twins.command(4_000_000)
    assert command is not None
    thrusts, torques = command
    assert len(thrusts) == 8 and len(torques) == len(PLANT_JOINTS)
    expected = current_to_torque_n_m(drives['joint_3'], 300.0)
    assert torques[PLANT_JOINTS.index('joint_3')] == pytest.approx(expected)
    assert all(math.isfinite(t) for t in torques)



@pytest.mark.parametrize('bus', [False, True])
def test_the_stands_alpha5_bus_switch_gives_the_arm_twin_its_line(bus: bool) -> None:
    """``alpha5_bus`` (``twins.alpha5_bus`` on the simulator): the arm twin's RS-485 line.

    On, the twin keeps the line at the robot's baud; off (the default), it answers every
    frame at once.
    """
    stand = TwinStand(ROBOT, {**PORTS, 'alpha5_bus': bus}, lambda: 0.0, lambda line: None)
    try:
        assert (stand.arm.line is not None) is bus
        if bus:
            assert stand.arm.line.baud == load_alpha5(ROBOT).serial_baud
    finally:
        stand.stop()
