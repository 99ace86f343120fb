"""The CDR layouts of the topics every control period carries, fixed for one robot.

Frames and joint names are those the graph publishes (docs/interfaces.md): a payload of
another layout still reads through `uvms_common.cdr_codecs.RawDecoder`'s rclpy fallback.
"""

from __future__ import annotations

from collections.abc import Sequence

from geometry_msgs.msg import (
    PoseStamped,
    PoseWithCovarianceStamped,
    TwistWithCovarianceStamped,
    WrenchStamped,
)
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Imu, JointState

from uvms_common.cdr_codecs import MessageCodec
from uvms_msgs.msg import (
    ActuatorCommand,
    ContactState,
    ControllerState,
    GeneralizedForce,
    ThrusterState,
)

MAP_NED = 'map_ned'
BASE_LINK_FRD = 'base_link_frd'
FT_SENSOR_LINK = 'ft_sensor_link'
DVL_LINK = 'dvl_link'
#: The ThrusterState arrays, one value per thruster each.
THRUSTER_ARRAYS = ('desired_thrust', 'actual_thrust', 'propeller_speed', 'reference_speed',
                   'motor_current')


def clock_codec() -> MessageCodec:
    """rosgraph_msgs/Clock (``/clock``)."""
    return MessageCodec(Clock)


def joint_state_codec(joint_names: Sequence[str]) -> MessageCodec:
    """sensor_msgs/JointState of the arm (``joint_states``): names, positions, rates, torques."""
    n = len(joint_names)
    return MessageCodec(JointState, {'header.frame_id': '', 'name': list(joint_names),
                                     'position': n, 'velocity': n, 'effort': n})


def odometry_codec() -> MessageCodec:
    """nav_msgs/Odometry of the vehicle (``odometry``): pose in map_ned, twist in FRD."""
    return MessageCodec(Odometry, {'header.frame_id': MAP_NED, 'child_frame_id': BASE_LINK_FRD})


def wrench_codec() -> MessageCodec:
    """geometry_msgs/WrenchStamped of the wrist sensor (``wrench``)."""
    return MessageCodec(WrenchStamped, {'header.frame_id': FT_SENSOR_LINK})


def pose_codec() -> MessageCodec:
    """geometry_msgs/PoseStamped of the end effector in map_ned (``ee_pose``)."""
    return MessageCodec(PoseStamped, {'header.frame_id': MAP_NED})


def contact_codec() -> MessageCodec:
    """uvms_msgs/ContactState, the contact ground truth in map_ned (``contact``)."""
    return MessageCodec(ContactState, {'header.frame_id': MAP_NED})


def generalized_force_codec(joint_names: Sequence[str]) -> MessageCodec:
    """uvms_msgs/GeneralizedForce (``command/generalized_force``)."""
    return MessageCodec(GeneralizedForce, {'header.frame_id': BASE_LINK_FRD,
                                           'joint_names': list(joint_names),
                                           'joint_torques': len(joint_names)})


def controller_state_codec() -> MessageCodec:
    """uvms_msgs/ControllerState in map_ned (``controller/state``)."""
    return MessageCodec(ControllerState, {'header.frame_id': MAP_NED})


def actuator_command_codec(n_thrusters: int, joint_names: Sequence[str]) -> MessageCodec:
    """uvms_msgs/ActuatorCommand (``command/actuators``)."""
    return MessageCodec(ActuatorCommand, {'header.frame_id': BASE_LINK_FRD,
                                          'thrust': n_thrusters,
                                          'joint_names': list(joint_names),
                                          'joint_torques': len(joint_names)})


def thruster_state_codec(n_thrusters: int) -> MessageCodec:
    """uvms_msgs/ThrusterState (``thrusters/state``)."""
    return MessageCodec(ThrusterState, {'header.frame_id': BASE_LINK_FRD,
                                        **dict.fromkeys(THRUSTER_ARRAYS, n_thrusters)})


def imu_codec() -> MessageCodec:
    """sensor_msgs/Imu in base_link_frd, AHRS orientation in map_ned (``imu``)."""
    return MessageCodec(Imu, {'header.frame_id': BASE_LINK_FRD})


def dvl_codec() -> MessageCodec:
    """geometry_msgs/TwistWithCovarianceStamped of the DVL in dvl_link (``dvl``)."""
    return MessageCodec(TwistWithCovarianceStamped, {'header.frame_id': DVL_LINK})


def pose_covariance_codec() -> MessageCodec:
    """geometry_msgs/PoseWithCovarianceStamped in map_ned (``depth``, ``position_fix``)."""
    return MessageCodec(PoseWithCovarianceStamped, {'header.frame_id': MAP_NED})


def navigation_codecs() -> dict[str, MessageCodec]:
    """The navigation topics' codecs (no robot-dependent length), by relative topic name."""
    return {
        'imu': imu_codec(),
        'dvl': dvl_codec(),
        'depth': pose_covariance_codec(),
        'position_fix': pose_covariance_codec(),
        'odometry/filtered': odometry_codec(),
    }


def hot_codecs(joint_names: Sequence[str], n_thrusters: int) -> dict[str, MessageCodec]:
    """Every hot topic's codec for one robot, by topic name (relative, as the nodes use them).

    The navigation topics (`navigation_codecs`) are among them: the simulator publishes them
    and the estimator answers each state with ``odometry/filtered`` when navigation is on.
    """
    return {
        '/clock': clock_codec(),
        'joint_states': joint_state_codec(joint_names),
        'odometry': odometry_codec(),
        'wrench': wrench_codec(),
        'ee_pose': pose_codec(),
        'contact': contact_codec(),
        'command/generalized_force': generalized_force_codec(joint_names),
        'controller/state': controller_state_codec(),
        'command/actuators': actuator_command_codec(n_thrusters, joint_names),
        'thrusters/state': thruster_state_codec(n_thrusters),
        **navigation_codecs(),
    }
