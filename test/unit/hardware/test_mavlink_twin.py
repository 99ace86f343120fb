"""The ArduSub twin follows ArduPilot's documented behaviour, seen from a bare pymavlink GCS."""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest
from pymavlink import mavutil
from uvms_twins.ardusub_twin import ArduSubTwin

MAV = mavutil.mavlink


def wait(condition: Callable[[], bool], timeout_s: float, what: str) -> None:
    """Poll until condition() or fail naming what."""
    end = time.monotonic() + timeout_s
    while not condition():
        assert time.monotonic() < end, f'timed out waiting for {what}'
        time.sleep(0.005)


def gcs(twin: ArduSubTwin, system_id: int = 255) -> Any:
    """A bare pymavlink connection to the twin that has been heard (MAVLink 2)."""
    os.environ['MAVLINK20'] = '1'
    conn = mavutil.mavlink_connection(twin.url, source_system=system_id, source_component=190,
                                      dialect='ardupilotmega')
    conn.mav.heartbeat_send(MAV.MAV_TYPE_GCS, MAV.MAV_AUTOPILOT_INVALID, 0, 0, 0)
    return conn


def override(conn: Any, values_1_8: list[int], values_9_18: list[int] | None = None) -> None:
    """RC_CHANNELS_OVERRIDE to system 1, component 1."""
    conn.mav.rc_channels_override_send(1, 1, *values_1_8, *(values_9_18 or [0] * 10))


@pytest.fixture
def twin() -> Iterator[ArduSubTwin]:
    """A twin whose outputs 1-2 are RCIN1-2 passthrough and overrides expire after 0.3 s."""
    with ArduSubTwin(parameters={'SERVO1_FUNCTION': 51, 'SERVO2_FUNCTION': 52,
                                 'RC_OVERRIDE_TIME': 0.3}) as running:
        yield running


def test_heartbeat_says_ardupilot_submarine(twin: ArduSubTwin) -> None:
    """HEARTBEAT: MAV_TYPE_SUBMARINE, MAV_AUTOPILOT_ARDUPILOTMEGA, disarmed."""
    conn = gcs(twin)
    msg = conn.recv_match(type='HEARTBEAT', blocking=True, timeout=3.0)
    assert (msg.type, msg.autopilot) == (MAV.MAV_TYPE_SUBMARINE, MAV.MAV_AUTOPILOT_ARDUPILOTMEGA)
    assert not msg.base_mode & MAV.MAV_MODE_FLAG_SAFETY_ARMED
    conn.close()


def test_overrides_only_from_the_gcs_system_id(twin: ArduSubTwin) -> None:
    """System 254 is ignored while MAV_GCS_SYSID is 255; 255 is obeyed."""
    stranger, ours = gcs(twin, 254), gcs(twin, 255)
    override(stranger, [1700] * 8)
    wait(lambda: len(twin.overrides()) == 1, 1.0, 'the stranger override')
    assert twin.servo_outputs_us()[:2] == [0, 0] and not twin.overrides()[-1].obeyed
    override(ours, [1600] * 8)
    wait(lambda: twin.servo_outputs_us()[:2] == [1600, 1600], 1.0, 'our override')
    stranger.close()
    ours.close()


def test_channel_semantics_ignore_and_release(twin: ArduSubTwin) -> None:
    """65535 keeps channel 1's override; 0 releases it (passthrough keeps its last value)."""
    conn = gcs(twin)
    override(conn, [1600, 1400] + [65535] * 6)
    wait(lambda: twin.active_override_us(1) == 1600, 1.0, 'the override')
    override(conn, [65535, 1450] + [65535] * 6)
    wait(lambda: twin.active_override_us(2) == 1450, 1.0, 'channel 2 changed')
    assert twin.active_override_us(1) == 1600
    # The input takes it at the next 50 Hz RC read (one released before it is never read).
    wait(lambda: twin.servo_outputs_us()[1] == 1450, 1.0, 'the RC read of channel 2')
    override(conn, [0] * 8)
    wait(lambda: twin.active_override_us(1) == 0, 1.0, 'the release')
    assert twin.servo_outputs_us()[:2] == [1600, 1450]  # unknown in the docs: unsafe reading
    conn.close()


def test_overrides_expire_after_rc_override_time(twin: ArduSubTwin) -> None:
    """No override for RC_OVERRIDE_TIME (0.3 s here): the channel's override is gone."""
    conn = gcs(twin)
    override(conn, [1700] * 8)
    wait(lambda: twin.active_override_us(1) == 1700, 1.0, 'the override')
    time.sleep(0.4)
    assert twin.active_override_us(1) == 0
    assert twin.servo_outputs_us()[0] == 1700  # the passthrough output keeps it: unknown
    conn.close()


def test_parameters_arming_and_message_intervals(twin: ArduSubTwin) -> None:
    """PARAM_VALUE answers, an unknown name none; arm acknowledged; 511 starts a stream."""
    conn = gcs(twin)
    conn.mav.param_request_read_send(1, 1, b'RC_OVERRIDE_TIME', -1)
    msg = conn.recv_match(type='PARAM_VALUE', blocking=True, timeout=2.0)
    assert (msg.param_id, msg.param_value) == ('RC_OVERRIDE_TIME', pytest.approx(0.3))
    conn.mav.param_request_read_send(1, 1, b'NO_SUCH_PARAM', -1)
    assert conn.recv_match(type='PARAM_VALUE', blocking=True, timeout=0.3) is None
    conn.mav.command_long_send(1, 1, MAV.MAV_CMD_COMPONENT_ARM_DISARM, 0, 1, 0, 0, 0, 0, 0, 0)
    ack = conn.recv_match(type='COMMAND_ACK', blocking=True, timeout=2.0)
    assert ack.result == MAV.MAV_RESULT_ACCEPTED and twin.armed
    twin.set_plant_state(depth_m=1.0)
    conn.mav.command_long_send(1, 1, MAV.MAV_CMD_SET_MESSAGE_INTERVAL, 0,
                               MAV.MAVLINK_MSG_ID_SCALED_PRESSURE2, 20000, 0, 0, 0, 0, 0)
    pressures = [conn.recv_match(type='SCALED_PRESSURE2', blocking=True, timeout=1.0)
                 for _ in range(5)]
    assert all(p is not None for p in pressures)
    assert pressures[-1].press_abs == pytest.approx(1013.25 + 98.0665, abs=0.01)
    conn.close()
