"""Realistic graph messages for the recording tests and benchmark, serialized by rosbags."""

from __future__ import annotations

from typing import Any

import numpy as np
from uvms_recording.typestore import uvms_typestore

#: (topic, type) of the graph topics the fixtures produce, as the recorder names them.
GRAPH_TOPICS = (
    ('/clock', 'rosgraph_msgs/msg/Clock'),
    ('/uvms/joint_states', 'sensor_msgs/msg/JointState'),
    ('/uvms/odometry', 'nav_msgs/msg/Odometry'),
    ('/uvms/wrench', 'geometry_msgs/msg/WrenchStamped'),
    ('/uvms/command/generalized_force', 'uvms_msgs/msg/GeneralizedForce'),
    ('/uvms/controller/state', 'uvms_msgs/msg/ControllerState'),
)


def _stamp(t_ns: int) -> Any:
    types = uvms_typestore().types
    return types['builtin_interfaces/msg/Time'](sec=t_ns // 10**9, nanosec=t_ns % 10**9)


def _header(t_ns: int, frame_id: str) -> Any:
    return uvms_typestore().types['std_msgs/msg/Header'](stamp=_stamp(t_ns), frame_id=frame_id)


def make_message(type_name: str, t_ns: int, k: int) -> Any:
    """A plausible message of the graph at step k, stamped t_ns (rosbags dataclass)."""
    types = uvms_typestore().types
    vec = types['geometry_msgs/msg/Vector3']
    point = types['geometry_msgs/msg/Point']
    x = 0.001 * k
    if type_name == 'rosgraph_msgs/msg/Clock':
        return types[type_name](clock=_stamp(t_ns))
    if type_name == 'sensor_msgs/msg/JointState':
        return types[type_name](
            header=_header(t_ns, ''),
            name=['joint_1', 'joint_2', 'joint_3'],
            position=np.array([x, -x, 2 * x]),
            velocity=np.array([0.1, 0.2, 0.3]),
            effort=np.array([1.0, 2.0, 3.0]),
        )
    if type_name == 'nav_msgs/msg/Odometry':
        pose = types['geometry_msgs/msg/Pose'](
            position=point(x=x, y=0.0, z=1.0),
            orientation=types['geometry_msgs/msg/Quaternion'](x=0.0, y=0.0, z=0.0, w=1.0),
        )
        twist = types['geometry_msgs/msg/Twist'](linear=vec(x=x, y=0.0, z=0.0),
                                                 angular=vec(x=0.0, y=0.0, z=0.01))
        return types[type_name](
            header=_header(t_ns, 'map_ned'),
            child_frame_id='base_link_frd',
            pose=types['geometry_msgs/msg/PoseWithCovariance'](pose=pose,
                                                               covariance=np.zeros(36)),
            twist=types['geometry_msgs/msg/TwistWithCovariance'](twist=twist,
                                                                 covariance=np.zeros(36)),
        )
    if type_name == 'geometry_msgs/msg/WrenchStamped':
        wrench = types['geometry_msgs/msg/Wrench'](force=vec(x=150.0 + x, y=0.0, z=0.0),
                                                   torque=vec(x=0.0, y=0.0, z=0.0))
        return types[type_name](header=_header(t_ns, 'ft_sensor_link'), wrench=wrench)
    if type_name == 'uvms_msgs/msg/GeneralizedForce':
        wrench = types['geometry_msgs/msg/Wrench'](force=vec(x=10.0 + x, y=-1.0, z=2.0),
                                                   torque=vec(x=0.1, y=0.2, z=-0.3))
        return types[type_name](
            header=_header(t_ns, 'base_link_frd'),
            vehicle_wrench=wrench,
            joint_names=['joint_1', 'joint_2', 'joint_3'],
            joint_torques=np.array([1.0 + x, 2.0, 3.0]),
        )
    if type_name == 'uvms_msgs/msg/ControllerState':
        return types[type_name](
            header=_header(t_ns, 'map_ned'),
            weight=0.5,
            phase=1,
            contact_force=vec(x=100.0, y=0.0, z=0.0),
            desired_force=vec(x=150.0, y=0.0, z=0.0),
            position=point(x=1.7, y=0.0, z=0.5 + x),
            desired_position=point(x=1.7, y=0.0, z=0.5),
            velocity=vec(x=0.0, y=0.0, z=0.0),
            desired_velocity=vec(x=0.0, y=0.0, z=0.0),
            normal_velocity=0.0,
            impedance_force=vec(x=1.0, y=0.0, z=0.0),
            hybrid_force=vec(x=2.0, y=0.0, z=0.0),
            command_force=vec(x=1.5, y=0.0, z=0.0),
        )
    raise KeyError(type_name)


def make_cdr(type_name: str, t_ns: int, k: int) -> bytes:
    """The message of make_message serialized as CDR (rosbags)."""
    return bytes(uvms_typestore().serialize_cdr(make_message(type_name, t_ns, k), type_name))


def graph_messages(n_steps: int) -> list[tuple[str, str, int, bytes]]:
    """Lockstep steps of 1 ms (n_steps) of every graph topic, as (topic, type, t_ns, cdr)."""
    out = []
    for k in range(n_steps):
        t_ns = k * 1_000_000
        for topic, type_name in GRAPH_TOPICS:
            out.append((topic, type_name, t_ns, make_cdr(type_name, t_ns, k)))
    return out
