"""What the recorder records: the graph's topics, their message classes and QoS."""

from __future__ import annotations

import importlib
from typing import Any

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from uvms_recording.errors import RecordingError
from uvms_recording.mcap_writer import QosDescription
from uvms_recording.typestore import InterfaceError, normalize_type_name

#: The graph's topics as 'name:type' (DESIGN.md); relative names resolve in the node's
#: namespace (/uvms by default), /clock, /tf and /tf_static are absolute.
DEFAULT_TOPICS = (
    '/clock:rosgraph_msgs/msg/Clock',
    'joint_states:sensor_msgs/msg/JointState',
    'odometry:nav_msgs/msg/Odometry',
    'wrench:geometry_msgs/msg/WrenchStamped',
    'ee_pose:geometry_msgs/msg/PoseStamped',
    'contact:uvms_msgs/msg/ContactState',
    'command/generalized_force:uvms_msgs/msg/GeneralizedForce',
    'controller/state:uvms_msgs/msg/ControllerState',
    'controller/task_record:uvms_msgs/msg/ContactTaskRecord',
    'controller/mode:std_msgs/msg/String',
    'command/actuators:uvms_msgs/msg/ActuatorCommand',
    'thrusters/state:uvms_msgs/msg/ThrusterState',
    'thrusters/health:uvms_msgs/msg/ThrusterHealth',
    '/tf:tf2_msgs/msg/TFMessage',
    '/tf_static:tf2_msgs/msg/TFMessage',
    '/robot_description:std_msgs/msg/String',
    'markers:visualization_msgs/msg/MarkerArray',
    'ocean/current:geometry_msgs/msg/TwistStamped',
)

#: Depth of the recorder's subscriptions: lockstep publishes in bursts faster than real time,
#: and a batch (``take_period_s``) takes what arrived since the last one.
SUBSCRIPTION_DEPTH = 1000


def parse_topic_spec(spec: str) -> tuple[str, str]:
    """Split a 'topic:pkg/msg/Type' entry of the `topics` parameter.

    Raises:
        RecordingError: The entry is not 'topic:type' with a valid type name.

    """
    topic, separator, type_name = spec.rpartition(':')
    if not separator or not topic or not type_name:
        msg = f"parameter 'topics': entry {spec!r} is not 'topic:pkg/msg/Type'"
        raise RecordingError(msg)
    try:
        return topic, normalize_type_name(type_name)
    except InterfaceError as error:
        msg = f"parameter 'topics': entry {spec!r}: {error}"
        raise RecordingError(msg) from None


def message_class(type_name: str) -> type[Any]:
    """The Python message class of 'pkg/msg/Type', imported from its message package.

    Raises:
        RecordingError: The package or the type cannot be imported.

    """
    package, _, name = normalize_type_name(type_name).split('/')
    try:
        module = importlib.import_module(f'{package}.msg')
        return getattr(module, name)  # type: ignore[no-any-return]
    except (ImportError, AttributeError):
        msg = f'message type {type_name!r} cannot be imported (is package {package!r} built?)'
        raise RecordingError(msg) from None


def publisher_qos(topic: str) -> QosDescription:
    """QoS the graph's publishers offer on a topic, as tf2_ros and our nodes publish.

    /tf_static and /robot_description are latched (reliable, transient local, depth 1, as
    tf2_ros and robot_state_publisher offer them), /tf reliable with depth 100; every other
    graph publisher is reliable, volatile, keep last 10 (rclpy's default).
    """
    if topic.endswith(('/tf_static', '/robot_description')):
        return QosDescription(durability='transient_local', depth=1)
    if topic.endswith('/tf'):
        return QosDescription(depth=100)
    return QosDescription()


def subscription_qos(topic: str) -> QoSProfile:
    """QoS of the recorder's subscription, compatible with the publisher and deep enough.

    /clock is subscribed best effort as rclpy's own time source does, which matches a
    reliable or a best-effort /clock publisher alike.
    """
    offered = publisher_qos(topic)
    if offered.durability == 'transient_local':
        return QoSProfile(
            history=HistoryPolicy.KEEP_LAST,
            depth=offered.depth,
            reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.TRANSIENT_LOCAL,
        )
    reliability = (ReliabilityPolicy.BEST_EFFORT if topic == '/clock'
                   else ReliabilityPolicy.RELIABLE)
    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST,
        depth=SUBSCRIPTION_DEPTH,
        reliability=reliability,
        durability=DurabilityPolicy.VOLATILE,
    )
