"""The simulator's raw navigation payloads carry exactly what its typed messages carry."""

from __future__ import annotations

import functools
from typing import Any

import numpy as np
import pytest
from rclpy.serialization import deserialize_message
from uvms_model.nav_sensor_parameters import NavigationParameters
from uvms_model.nav_sensors import (
    DepthReading,
    DvlReading,
    ImuReading,
    NavigationSensors,
    NavigationTruth,
    PositionFixReading,
)
from uvms_sim.raw_conversions import RawNavigationMessages

from uvms_sim import navigation_topics as typed_builders

GYRO_VAR, ACCEL_VAR = 2.5e-6, 4.0e-4


def plain(msg: Any) -> dict[str, Any]:
    """A message as nested plain values, to compare two messages field by field."""
    out: dict[str, Any] = {}
    for name in type(msg).get_fields_and_field_types():
        value = getattr(msg, name)
        out[name] = plain(value) if hasattr(value, 'get_fields_and_field_types') else (
            list(value) if not isinstance(value, str | bool | int | float) else value)
    return out


@functools.cache
def readings() -> list[Any]:
    """Readings of every sensor (a position fix on) over 2 s of a moving, turning vehicle."""
    params = NavigationParameters.from_flat_dict({
        'world.seabed_depth_m': 6.0, 'navigation.position_fix.enabled': True})
    sensors = NavigationSensors(params, seed=3)
    out = []
    for k in range(0, 2001, 5):
        t = k * 1e-3
        truth = NavigationTruth.of([0.2 * t, -0.1 * t, 2.0 + 0.05 * t], [0.1, -0.05, 0.3 * t],
                                   [0.2, 0.1, 0.05], [0.01, -0.02, 0.3], [0.0, 0.01, 0.0])
        out.extend(sensors.sample(k * 1_000_000, truth))
    return out


def of_type(kind: type, valid: bool = True) -> list[Any]:
    """The readings of one sensor (the DVL's with bottom lock only, as published)."""
    found = [r for r in readings() if isinstance(r, kind)
             and (not isinstance(r, DvlReading) or r.valid == valid)]
    assert found, kind.__name__
    return found[:5]


def test_imu_payload_equals_the_typed_imu() -> None:
    """sensor_msgs/Imu: orientation, rate, specific force, every covariance, frame, stamp."""
    raw = RawNavigationMessages(GYRO_VAR, ACCEL_VAR)
    for r in of_type(ImuReading):
        payload = raw.imu(r.t_ns, r.rpy, r.rpy_sigma, r.w_body, r.f_body)
        expected = typed_builders.imu_message(r, GYRO_VAR, ACCEL_VAR)
        assert plain(deserialize_message(payload, type(expected))) == plain(expected)


def test_dvl_payload_equals_the_typed_dvl() -> None:
    """geometry_msgs/TwistWithCovarianceStamped in dvl_link, sigma^2 on the diagonal."""
    raw = RawNavigationMessages(GYRO_VAR, ACCEL_VAR)
    for r in of_type(DvlReading):
        payload = raw.dvl(r.t_ns, r.v_dvl, r.sigma_m_s)
        expected = typed_builders.dvl_message(r)
        assert plain(deserialize_message(payload, type(expected))) == plain(expected)


@pytest.mark.parametrize('bias_max_m', [0.0, 0.02])
def test_depth_payload_equals_the_typed_depth(bias_max_m: float) -> None:
    """Depth as a pose in map_ned with only z's variance finite (noise + uniform bias)."""
    raw = RawNavigationMessages(GYRO_VAR, ACCEL_VAR)
    unused = typed_builders.UNUSED_VARIANCE
    for r in of_type(DepthReading):
        variance = r.sigma_m ** 2 + bias_max_m ** 2 / 3.0
        payload = raw.pose(r.t_ns, (0.0, 0.0, r.depth_m), (unused, unused, variance))
        expected = typed_builders.depth_message(r, bias_max_m)
        assert plain(deserialize_message(payload, type(expected))) == plain(expected)


def test_position_fix_payload_equals_the_typed_fix() -> None:
    """A fix as a pose in map_ned with the position's variances."""
    raw = RawNavigationMessages(GYRO_VAR, ACCEL_VAR)
    for r in of_type(PositionFixReading):
        payload = raw.pose(r.t_ns, r.p_ned, (r.sigma_m ** 2).tolist())
        expected = typed_builders.position_fix_message(r)
        assert plain(deserialize_message(payload, type(expected))) == plain(expected)
        np.testing.assert_array_equal(
            np.array(deserialize_message(payload, type(expected)).pose.covariance)[[0, 7, 14]],
            r.sigma_m ** 2)
