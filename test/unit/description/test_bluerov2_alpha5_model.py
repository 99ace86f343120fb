"""The bluerov2_alpha5 robot data: masses, the Alpha 5's DH kinematics, the thruster layout."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml

ROBOT = Path(__file__).resolve().parents[3] / 'src' / 'uvms_description' / 'robots' / (
    'bluerov2_alpha5')
URDF = ROBOT / 'robot.urdf'
THRUSTERS = ROBOT / 'thrusters.yaml'

#: Reach Alpha 5 standard DH table (Reach, "Alpha MKII Kinematic and Dynamic Properties" v7):
#: rows (d m, theta offset rad, a m, alpha rad); the joint angle q_i adds to theta of row i.
THETA_C = math.atan(40.0 / 145.3)
DH_ROWS = (
    (0.0462, math.pi, 0.020, math.pi / 2.0),
    (0.0, THETA_C - math.pi / 2.0, math.hypot(0.040, 0.1453), math.pi),
    (0.0, THETA_C - math.pi / 2.0, 0.020, -math.pi / 2.0),
    (-0.180, math.pi / 2.0, 0.0, math.pi / 2.0),
    (0.0, -math.pi / 2.0, 0.0, 0.0),  # fixed: the end-effector frame
)
#: DH frame 0 in base_link_frd: the mount (0.19, 0, 0.12) m, z0 along the base tube (forward),
#: x0 down (z of base_link_frd).
MOUNT = np.array([
    [0.0, 0.0, 1.0, 0.19],
    [0.0, -1.0, 0.0, 0.0],
    [1.0, 0.0, 0.0, 0.12],
    [0.0, 0.0, 0.0, 1.0],
])
#: The working pose (rad): jaw forward, below the front of the vehicle.
WORKING_POSE = np.array([math.pi, 1.5, 1.5, 0.0])
#: Reach's inertial table (kg): L0 the fixed base tube, L1..L4 the links of axes E, D, C, B.
ARM_MASSES = {'alpha_base_link': 0.234, 'link_1': 0.161, 'link_2': 0.380, 'link_3': 0.142,
              'link_4': 0.355}
VEHICLE_MASS = 13.5  # von Benzon et al. 2022, Table A1
SENSOR_MASS = 0.25  # assumed (docs/robots.md)

#: The blue stack's allocation matrix for the BlueROV2 Heavy (forward-starboard-down; rows x,
#: y, z, roll, pitch, yaw; columns T1..T8), as given in the robot notes.
BLUE_ALLOCATION = np.array([
    [-0.707, -0.707, 0.707, 0.707, 0.0, 0.0, 0.0, 0.0],
    [0.707, -0.707, 0.707, -0.707, 0.0, 0.0, 0.0, 0.0],
    [0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0],
    [0.0, 0.0, 0.0, 0.0, -0.21805, 0.21805, -0.21805, 0.21805],
    [0.0, 0.0, 0.0, 0.0, -0.12, -0.12, 0.12, 0.12],
    [0.1888, -0.1888, -0.1888, 0.1888, 0.0, 0.0, 0.0, 0.0],
])
#: ArduSub SUB_FRAME_VECTORED_6DOF motor factors (roll, pitch, yaw, throttle, forward,
#: lateral) of M1..M8 (AP_Motors6DOF.cpp). A positive throttle (climb) is -z.
ARDUSUB_FACTORS = np.array([
    [0, 0, 1, 0, -1, 1],
    [0, 0, -1, 0, -1, -1],
    [0, 0, -1, 0, 1, 1],
    [0, 0, 1, 0, 1, -1],
    [1, -1, 0, -1, 0, 0],
    [-1, -1, 0, -1, 0, 0],
    [1, 1, 0, -1, 0, 0],
    [-1, 1, 0, -1, 0, 0],
])


def dh_transform(d: float, theta: float, a: float, alpha: float) -> np.ndarray:
    """Standard DH link transform Rz(theta) Tz(d) Tx(a) Rx(alpha) (4 x 4)."""
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return np.array([
        [ct, -st * ca, st * sa, a * ct],
        [st, ct * ca, -ct * sa, a * st],
        [0.0, sa, ca, d],
        [0.0, 0.0, 0.0, 1.0],
    ])


def dh_end_effector(q: np.ndarray) -> np.ndarray:
    """Pose of the DH end-effector frame in base_link_frd, the direct product of the table."""
    pose = MOUNT.copy()
    for i, (d, offset, a, alpha) in enumerate(DH_ROWS):
        pose = pose @ dh_transform(d, offset + (q[i] if i < q.size else 0.0), a, alpha)
    return pose


def thruster_matrix() -> np.ndarray:
    """6 x 8 configuration matrix [d_i; p_i x d_i] of thrusters.yaml."""
    document = yaml.safe_load(THRUSTERS.read_text(encoding='utf-8'))
    thrusters = document['/**']['ros__parameters']['thrusters']
    positions = np.reshape(thrusters['positions_m'], (-1, 3))
    directions = np.reshape(thrusters['directions'], (-1, 3))
    return np.vstack([directions.T, np.cross(positions, directions).T])


@pytest.fixture(scope='module')
def model() -> pin.Model:
    """Pinocchio's model of the URDF (fixed base: the arm alone moves)."""
    return pin.buildModelFromXML(URDF.read_text(encoding='utf-8'))


def test_urdf_masses_are_the_published_ones() -> None:
    """Every mass is positive; vehicle, arm links and sensor are the chosen sources' values."""
    robot = ET.parse(URDF).getroot()
    masses = {link.get('name'): float(link.find('inertial/mass').get('value'))
              for link in robot.iter('link') if link.find('inertial') is not None}
    assert all(m > 0.0 for m in masses.values())
    assert masses['base_link_frd'] == VEHICLE_MASS
    assert masses['ft_sensor_link'] == SENSOR_MASS
    for name, mass in ARM_MASSES.items():
        assert masses[name] == pytest.approx(mass)
    assert sum(masses.values()) == pytest.approx(VEHICLE_MASS + 1.272 + SENSOR_MASS)


def test_pinocchio_total_mass_matches_the_urdf(model: pin.Model) -> None:
    """Pinocchio merges the fixed links: its bodies sum to the same 15.02 kg."""
    total = sum(inertia.mass for inertia in model.inertias)
    assert total == pytest.approx(VEHICLE_MASS + 1.272 + SENSOR_MASS, abs=1e-9)
    assert model.nq == 4
    assert [model.names[i] for i in range(1, model.njoints)] == [
        'joint_1', 'joint_2', 'joint_3', 'joint_4']


def test_every_link_inertia_is_physical(model: pin.Model) -> None:
    """Each body's rotational inertia is positive definite and meets the triangle inequality."""
    for inertia in model.inertias[1:]:
        moments = np.linalg.eigvalsh(inertia.inertia)
        assert moments.min() > 0.0
        assert moments.sum() - 2.0 * moments.max() >= -1e-12


@pytest.mark.parametrize('seed', range(6))
def test_forward_kinematics_equals_the_dh_table(model: pin.Model, seed: int) -> None:
    """ee_link from Pinocchio equals the DH product at random joint angles (to 1e-9 m, rad)."""
    q = np.random.default_rng(seed).uniform(-math.pi, math.pi, model.nq)
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    pose = data.oMf[model.getFrameId('ee_link')].homogeneous
    np.testing.assert_allclose(pose, dh_end_effector(q), atol=1e-9)


def test_sensor_frame_is_the_end_effector_frame(model: pin.Model) -> None:
    """ft_sensor_link reports in ee_link's pose, as the stack's sensor frames do."""
    data = model.createData()
    pin.framesForwardKinematics(model, data, WORKING_POSE + 0.3)
    ee = data.oMf[model.getFrameId('ee_link')]
    sensor = data.oMf[model.getFrameId('ft_sensor_link')]
    np.testing.assert_allclose(sensor.homogeneous, ee.homogeneous, atol=1e-12)


def test_arm_hangs_below_the_front_and_works_forward(model: pin.Model) -> None:
    """At the working pose the jaw points forward, ahead of and below the vehicle frame."""
    data = model.createData()
    pin.framesForwardKinematics(model, data, WORKING_POSE)
    ee = data.oMf[model.getFrameId('ee_link')]
    assert ee.translation[0] > 0.457 / 2.0 + 0.1
    assert ee.translation[2] > 0.254 / 2.0
    np.testing.assert_allclose(ee.rotation[:, 0], [1.0, 0.0, 0.0], atol=1e-2)


def test_thruster_configuration_matrix_has_full_rank() -> None:
    """Eight thrusters span all six body wrench directions."""
    assert np.linalg.matrix_rank(thruster_matrix()) == 6


def test_thruster_signs_are_ardusub_vectored_6dof() -> None:
    """Each column has ArduSub's sign wherever ArduSub's factor is non-zero."""
    matrix = thruster_matrix()
    # ArduSub rows (roll, pitch, yaw, climb, forward, lateral) in our rows' terms.
    ours = np.vstack([matrix[3], matrix[4], matrix[5], -matrix[2], matrix[0], matrix[1]]).T
    nonzero = ARDUSUB_FACTORS != 0
    np.testing.assert_array_equal(np.sign(ours[nonzero]), ARDUSUB_FACTORS[nonzero])


def test_thruster_matrix_is_blue_stacks_with_its_simplifications() -> None:
    """Blue's matrix once our horizontal thrusters sit in O's plane and the vertical pairs swap.

    Blue puts the horizontal thrusters in the plane of O (no roll/pitch from their 8.5 cm
    depth) and numbers the vertical thrusters left/right the other way round (T5 front left);
    von Benzon and ArduSub put T5 front right.
    """
    matrix = thruster_matrix()
    matrix[3:5, :4] = 0.0
    swapped = matrix[:, [0, 1, 2, 3, 5, 4, 7, 6]]
    np.testing.assert_allclose(swapped, BLUE_ALLOCATION, atol=1e-3)
