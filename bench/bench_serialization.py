"""Throughput of genuine rclpy's CDR serialization, with rosbags' serializer as baseline.

Run: ``.venv/bin/python bench/bench_serialization.py``. Prints messages per second (best of
several repeats) for ``rclpy.serialization.serialize_message`` / ``deserialize_message``
(the generated C typesupport behind rmw_fastrtps_cpp) of JointState (9 joints), Odometry and
ControllerState, the same for rosbags' ``serialize_cdr`` / ``deserialize_cdr`` (pure
Python, what the recorder's readers use), and the cost of constructing and reading the
generated message classes. Figures only, no pass/fail.
"""

from __future__ import annotations

import sys
import timeit
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / 'src' / 'uvms_bringup'))

from geometry_msgs.msg import Vector3  # noqa: E402
from nav_msgs.msg import Odometry  # noqa: E402
from rclpy.serialization import deserialize_message, serialize_message  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402
from std_msgs.msg import Header  # noqa: E402
from uvms_recording.typestore import uvms_typestore  # noqa: E402

from uvms_msgs.msg import ControllerState  # noqa: E402

JOINTS = 9
REPEATS = 5


def rate(func: Callable[[], Any], min_time_s: float = 0.2) -> float:
    """Calls per second of func: best of REPEATS runs of at least min_time_s each."""
    timer = timeit.Timer(func)
    number, _ = timer.autorange()
    number = max(number, int(number * min_time_s / 0.2))
    best = min(timer.repeat(repeat=REPEATS, number=number))
    return number / best


def joint_state() -> JointState:
    """JointState of 9 joints with names, positions, velocities and efforts."""
    return JointState(
        header=Header(frame_id='base_link_frd'),
        name=[f'joint_{i + 1}' for i in range(JOINTS)],
        position=np.linspace(-1.0, 1.0, JOINTS),
        velocity=np.linspace(-0.5, 0.5, JOINTS),
        effort=np.linspace(-10.0, 10.0, JOINTS),
    )


def odometry() -> Odometry:
    """Odometry with a frame, pose, twist and diagonal covariances."""
    msg = Odometry(header=Header(frame_id='map_ned'), child_frame_id='base_link_frd')
    msg.pose.pose.position.x = 1.5
    msg.pose.covariance = np.eye(6).ravel()
    msg.twist.covariance = np.eye(6).ravel()
    return msg


def controller_state() -> ControllerState:
    """ControllerState with its vectors set."""
    msg = ControllerState(header=Header(frame_id='map_ned'), weight=0.5, phase=2)
    msg.contact_force = Vector3(x=150.0, y=0.0, z=0.0)
    msg.position.x = 1.7771
    return msg


def to_rosbags(msg: Any, typename: str) -> Any:
    """The rosbags object of an rclpy message (through CDR; used only to set up baselines)."""
    return uvms_typestore().deserialize_cdr(serialize_message(msg), typename)


def main() -> None:
    """Print the figures."""
    store = uvms_typestore()
    cases = [
        ('JointState (9 joints)', joint_state(), 'sensor_msgs/msg/JointState'),
        ('Odometry', odometry(), 'nav_msgs/msg/Odometry'),
        ('ControllerState', controller_state(), 'uvms_msgs/msg/ControllerState'),
    ]
    print(f'{"message":<24}{"op":<14}{"rclpy msg/s":>14}{"rosbags msg/s":>15}{"ratio":>8}')
    for label, msg, typename in cases:
        cls = type(msg)
        data = serialize_message(msg)
        twin = to_rosbags(msg, typename)
        ours_ser = rate(lambda m=msg: serialize_message(m))
        theirs_ser = rate(lambda t=twin, n=typename: store.serialize_cdr(t, n))
        ours_de = rate(lambda d=data, c=cls: deserialize_message(d, c))
        theirs_de = rate(lambda d=data, n=typename: store.deserialize_cdr(d, n))
        print(
            f'{label:<24}{"serialize":<14}{ours_ser:>14,.0f}{theirs_ser:>15,.0f}'
            f'{ours_ser / theirs_ser:>8.1f}'
        )
        print(
            f'{"":<24}{"deserialize":<14}{ours_de:>14,.0f}{theirs_de:>15,.0f}'
            f'{ours_de / theirs_de:>8.1f}'
        )
        theirs_bytes = len(store.serialize_cdr(twin, typename))
        print(f'{"":<24}{"bytes":<14}{len(data):>14}{theirs_bytes:>15}')

    names = [f'joint_{i + 1}' for i in range(JOINTS)]
    positions = [0.1 * i for i in range(JOINTS)]
    odom = odometry()
    vector = Vector3()
    costs = [
        ('JointState()', lambda: JointState()),
        (
            'JointState(name=, position=, velocity=, effort=) from lists',
            lambda: JointState(
                name=names, position=positions, velocity=positions, effort=positions
            ),
        ),
        ('Odometry()', lambda: Odometry()),
        ('ControllerState()', lambda: ControllerState()),
        ('read odom.pose.pose.position.x', lambda: odom.pose.pose.position.x),
        ('set vector.x = 1.0 (checked)', lambda: setattr(vector, 'x', 1.0)),
    ]
    print()
    print(f'{"operation":<62}{"us/call":>10}')
    for label, func in costs:
        print(f'{label:<62}{1e6 / rate(func):>10.2f}')


if __name__ == '__main__':
    main()
