"""Message conversions: quaternions, frames, the /tf tree and actuator command checks."""

import math

import numpy as np
import pytest
from builtin_interfaces.msg import Time
from uvms_model.kinematics import rot_ned_from_body
from uvms_model.nav_sensor_parameters import DvlParameters
from uvms_model.nav_sensors import Dvl
from uvms_sim.errors import CommandError

from uvms_model import UvmsModel
from uvms_msgs.msg import ActuatorCommand
from uvms_sim import conversions

JOINTS = ('joint_1', 'joint_2', 'joint_3')


def rotation_from_quaternion(x: float, y: float, z: float, w: float) -> np.ndarray:
    """Rotation matrix of a unit quaternion (independent oracle)."""
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


@pytest.mark.parametrize('rpy', [(0.0, 0.0, 0.0), (0.3, -0.2, 1.4), (-1.0, 0.5, -3.0)])
def test_odometry_quaternion_is_zyx_euler_rotation(rpy: tuple[float, float, float]) -> None:
    """The roll/pitch/yaw quaternion rotates like rot_ned_from_body (ZYX)."""
    quaternion = conversions.quaternion_from_rpy(*rpy)
    np.testing.assert_allclose(rotation_from_quaternion(*quaternion), rot_ned_from_body(*rpy),
                               atol=1e-12)


@pytest.mark.parametrize('rpy', [(0.0, 0.0, 0.0), (3.1, 0.2, -1.0), (0.1, -1.2, 3.0),
                                 (-2.9, 0.4, 2.8)])
def test_rotation_matrix_quaternion_round_trips(rpy: tuple[float, float, float]) -> None:
    """quaternion_from_rotation inverts the quaternion's rotation matrix, in every branch."""
    rot = rot_ned_from_body(*rpy)
    quaternion = conversions.quaternion_from_rotation(rot)
    assert quaternion[3] >= 0.0
    assert math.isclose(float(np.linalg.norm(quaternion)), 1.0, abs_tol=1e-12)
    np.testing.assert_allclose(rotation_from_quaternion(*quaternion), rot, atol=1e-12)


def test_ned_down_is_enu_minus_z_and_north_is_enu_y() -> None:
    """The map -> map_ned twin maps NED north to ENU y and NED down to ENU -z."""
    np.testing.assert_array_equal(conversions.ROT_ENU_FROM_NED @ [1.0, 0.0, 0.0], [0, 1, 0])
    np.testing.assert_array_equal(conversions.ROT_ENU_FROM_NED @ [0.0, 0.0, 1.0], [0, 0, -1])


def test_time_stamps_round_trip_in_integer_nanoseconds() -> None:
    """Stamps carry the simulated time exactly."""
    t_ns = 12_345_678_901
    stamp = conversions.time_from_ns(t_ns)
    assert (stamp.sec, stamp.nanosec) == (12, 345_678_901)
    assert conversions.ns_from_time(stamp) == t_ns


def test_odometry_pose_in_map_ned_twist_in_base_link_frd() -> None:
    """Odometry names map_ned and base_link_frd and carries eta and nu unchanged."""
    eta = np.array([1.0, 2.0, 3.0, 0.1, 0.2, 0.3])
    nu = np.array([0.5, 0.6, 0.7, 0.01, 0.02, 0.03])
    msg = conversions.odometry_message(5, eta, nu)
    assert (msg.header.frame_id, msg.child_frame_id) == ('map_ned', 'base_link_frd')
    assert msg.pose.pose.position.z == 3.0
    assert (msg.twist.twist.linear.x, msg.twist.twist.angular.z) == (0.5, 0.03)


def test_tf_tree_gives_each_frame_one_parent_and_reaches_map() -> None:
    """/tf and /tf_static form a tree rooted at map, base_link hanging under base_link_frd."""
    model = UvmsModel()
    poses = model.frame_poses(np.array([0, 0, 0, 0.1, 0.2, 0.3, 0.1, 0.4, -0.8]))
    tree = conversions.frame_parents(model.frame_names)
    transforms = [*conversions.tf_message(0, poses, tree).transforms,
                  *conversions.static_tf_message(0, poses).transforms]
    parents: dict[str, str] = {}
    for transform in transforms:
        assert transform.child_frame_id not in parents
        parents[transform.child_frame_id] = transform.header.frame_id
    for frame in parents:
        while frame in parents:
            frame = parents[frame]
        assert frame == 'map'
    assert {'map_ned', 'base_link', 'base_link_frd', 'ee_link', 'ft_sensor_link'} <= set(parents)


@pytest.mark.parametrize('rpy', [(0.0, 0.0, 0.0), (0.0, 0.0, math.pi / 4), (0.1, -0.3, 2.0)])
def test_dvl_link_is_fixed_to_base_link_frd_by_its_mounting(
        rpy: tuple[float, float, float]) -> None:
    """/tf_static's base_link_frd -> dvl_link takes a DVL velocity back to the body frame.

    The DVL model measures v_dvl = rot_body_from_dvl^T v_body (uvms_model.nav_sensors.Dvl);
    the transform's rotation (read through the quaternion oracle) must undo it, and its
    translation is the mounting position.
    """
    position = (-0.1, 0.02, 0.15)
    model = UvmsModel()
    poses = model.frame_poses(np.array([0, 0, 0, 0, 0, 0, 0.1, 0.4, -0.8]))
    transforms = conversions.static_tf_message(0, poses, (position, rpy)).transforms
    [dvl] = [t for t in transforms if t.child_frame_id == 'dvl_link']
    assert dvl.header.frame_id == 'base_link_frd'
    t = dvl.transform
    np.testing.assert_allclose([t.translation.x, t.translation.y, t.translation.z], position)
    rot_body_from_dvl = rotation_from_quaternion(t.rotation.x, t.rotation.y, t.rotation.z,
                                                 t.rotation.w)
    sensor = Dvl(DvlParameters(position_m=position, orientation_rpy=rpy), seed=1)
    v_body = np.array([0.3, -0.2, 0.1])
    v_dvl = sensor.rot_body_from_dvl.T @ v_body
    np.testing.assert_allclose(rot_body_from_dvl @ v_dvl, v_body, atol=1e-12)
    assert 'dvl_link' not in {t.child_frame_id
                              for t in conversions.static_tf_message(0, poses).transforms}


def test_tf_chain_reproduces_end_effector_pose() -> None:
    """Composing the /tf chain from map_ned to ee_link gives the model's end-effector pose."""
    q = np.array([0.3, -0.2, 0.5, 0.1, 0.2, 0.3, 0.1, 0.4, -0.8])
    model = UvmsModel()
    poses = model.frame_poses(q)
    tree = conversions.frame_parents(model.frame_names)
    by_child = {t.child_frame_id: t for t in conversions.tf_message(0, poses, tree).transforms}
    frame, p, rot = 'ee_link', np.zeros(3), np.eye(3)
    while frame != 'map_ned':
        t = by_child[frame].transform
        r = rotation_from_quaternion(t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w)
        p = r @ p + [t.translation.x, t.translation.y, t.translation.z]
        rot = r @ rot
        frame = by_child[frame].header.frame_id
    np.testing.assert_allclose(p, model.ee_position(q), atol=1e-12)
    np.testing.assert_allclose(rot, model.ee_rotation(q), atol=1e-12)


def make_command(thrust: list[float], torques: list[float],
                 names: list[str] | None = None) -> ActuatorCommand:
    """An actuator command stamped 2 ms."""
    msg = ActuatorCommand(thrust=thrust, joint_names=names or [], joint_torques=torques)
    msg.header.stamp = Time(sec=0, nanosec=2_000_000)
    return msg


def test_actuator_command_converts_with_its_stamp() -> None:
    """A valid command gives its stamp (ns), thrusts and torques."""
    stamp, thrusts, torques = conversions.actuator_command_arrays(
        make_command([1.0] * 8, [0.1, 0.2, 0.3]), 8, JOINTS)
    assert stamp == 2_000_000
    np.testing.assert_array_equal(thrusts, np.ones(8))
    np.testing.assert_array_equal(torques, [0.1, 0.2, 0.3])


def test_actuator_command_torques_follow_joint_names() -> None:
    """Joint torques given in another joint order are put back in the arm's order."""
    _, _, torques = conversions.actuator_command_arrays(
        make_command([0.0] * 8, [3.0, 1.0, 2.0], ['joint_3', 'joint_1', 'joint_2']), 8, JOINTS)
    np.testing.assert_array_equal(torques, [1.0, 2.0, 3.0])


@pytest.mark.parametrize(
    ('thrust', 'torques', 'names', 'field'),
    [
        ([0.0] * 7, [0.0] * 3, None, 'thrust has 7 values'),
        ([0.0] * 8, [0.0] * 2, None, 'joint_torques has 2 values'),
        ([0.0] * 7 + [math.nan], [0.0] * 3, None, 'thrust holds a non-finite'),
        ([0.0] * 8, [0.0, math.inf, 0.0], None, 'joint_torques holds a non-finite'),
        ([0.0] * 8, [0.0] * 3, ['joint_1', 'joint_2', 'wrist'], 'joint_names'),
    ],
)
def test_malformed_actuator_command_is_rejected_naming_the_field(
    thrust: list[float], torques: list[float], names: list[str] | None, field: str
) -> None:
    """Wrong sizes, NaN/Inf or unknown joint names raise CommandError naming the field."""
    with pytest.raises(CommandError, match=field):
        conversions.actuator_command_arrays(make_command(thrust, torques, names), 8, JOINTS)
