"""The bridges' sensor messages against the simulator's and the estimator's own readers."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest
from rclpy.serialization import serialize_message
from uvms_model.nav_sensors import DepthReading, DvlReading, ImuReading

from uvms_description.robots import robot_parameters
from uvms_hardware import bridge_messages as bm
from uvms_navigation import raw_conversions
from uvms_sim import conversions as sim_conversions
from uvms_sim import navigation_topics
from uvms_sim import raw_conversions as sim_raw

NAVIGATION = {k: p.value for k, p in robot_parameters('bluerov2_alpha5', 'estimator').items()}
NOISE = bm.ImuNoise.from_navigation(NAVIGATION)
SRC = Path(__file__).resolve().parents[3] / 'src'
#: Modules by their path under src/: the hardware package's cores and the twins' package.
PURE = [*(f'uvms_hardware/uvms_hardware/{name}' for name in (
    't200_curve.py', 'dvl_protocol.py', 'dvl_link.py', 'ardusub_link.py', 'ardusub_wire.py',
    'hardware_config.py')), 'uvms_twins/uvms_twins/ardusub_twin.py',
    'uvms_twins/uvms_twins/dvl_twin.py']


def test_frames_and_unused_variance_are_the_simulators() -> None:
    """map_ned, base_link_frd, dvl_link and 1e9 as uvms_sim names them."""
    assert (bm.MAP_NED, bm.BASE_LINK_FRD, bm.DVL_LINK) == (
        sim_conversions.MAP_NED, sim_conversions.BASE_LINK_FRD, sim_conversions.DVL_LINK)
    assert bm.UNUSED_VARIANCE == sim_raw.UNUSED_VARIANCE


@pytest.mark.parametrize('rpy', [(0.0, 0.0, 0.0), (0.2, -0.3, 2.5)])
def test_imu_message_equals_the_simulators_and_the_estimator_reads_it(
        rpy: tuple[float, float, float]) -> None:
    """Same frame, orientation, rates, specific force and covariances as uvms_sim's imu."""
    w, f = np.array([0.01, -0.02, 0.3]), np.array([0.1, 0.2, -9.8])
    x, y, z, qw = sim_conversions.quaternion_from_rpy(*rpy)
    ours = bm.imu_message(123_000_000_456, (qw, x, y, z), w, f, NOISE)
    sigma = np.sqrt(NOISE.rpy_var)
    theirs = navigation_topics.imu_message(
        ImuReading(123_000_000_456, w, f, np.array(rpy), sigma), NOISE.gyro_var, NOISE.accel_var)
    assert serialize_message(ours) == serialize_message(theirs)
    w_read, f_read, rpy_read = raw_conversions.imu_reader().read(serialize_message(ours))[1]
    np.testing.assert_allclose(w_read, w)
    np.testing.assert_allclose(f_read, f)
    np.testing.assert_allclose(rpy_read, rpy, atol=1e-9)


def test_depth_message_equals_the_simulators_and_the_estimator_reads_it() -> None:
    """Z down in map_ned, variance sigma^2 + bias^2/3 as uvms_sim's depth."""
    sigma, bias = NAVIGATION['navigation.depth.sigma_m'], NAVIGATION['navigation.depth.bias_max_m']
    ours = bm.depth_message(5_000_000_000, 2.5, sigma ** 2 + bias ** 2 / 3.0)
    theirs = navigation_topics.depth_message(DepthReading(5_000_000_000, 2.5, sigma), bias)
    assert serialize_message(ours) == serialize_message(theirs)
    assert raw_conversions.depth_reader().read(serialize_message(ours))[1] == (2.5,)


def test_dvl_message_equals_the_simulators_and_the_estimator_reads_it() -> None:
    """Velocity in dvl_link with an isotropic covariance, as uvms_sim's dvl."""
    v = np.array([0.3, -0.1, 0.02])
    ours = bm.dvl_message(7, v, (np.eye(3) * 0.004 ** 2).ravel())
    theirs = navigation_topics.dvl_message(DvlReading(7, True, v, 0.004, 2.0))
    assert serialize_message(ours) == serialize_message(theirs)
    np.testing.assert_allclose(raw_conversions.dvl_reader().read(serialize_message(ours))[1][0], v)


def test_depth_from_bar30_pressure() -> None:
    """(p - p_surface) / (rho g): 1 m of fresh water is 9806.65 Pa, 98.0665 hPa."""
    assert bm.depth_from_pressure(1013.25 + 98.0665, 101325.0, 1000.0) == pytest.approx(1.0)
    assert bm.depth_from_pressure(1013.25, 101325.0, 1000.0) == 0.0


@pytest.mark.parametrize('name', PURE)
def test_cores_and_twins_import_no_ros(name: str) -> None:
    """The MAVLink and DVL cores, the curve and the twins import neither rclpy nor messages."""
    tree = ast.parse((SRC / name).read_text())
    roots = {alias.name.split('.')[0] for node in ast.walk(tree) if isinstance(node, ast.Import)
             for alias in node.names}
    roots |= {node.module.split('.')[0] for node in ast.walk(tree)
              if isinstance(node, ast.ImportFrom) and node.module and node.level == 0}
    assert not {r for r in roots if r == 'rclpy' or r.endswith('_msgs')}
