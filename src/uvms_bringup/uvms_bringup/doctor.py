"""`uvms doctor`: which ROS 2 runtime is active, and whether our messages load and round-trip.

Works on both runtimes: with ROS 2 Jazzy sourced it imports the real rclpy and message
packages; without, the ros2_compat runtime. It touches ros2_compat only through its public
``rclpy_is_compat()`` and ``activate()``.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.metadata
import importlib.util
import os
import platform
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO

if TYPE_CHECKING:
    from collections.abc import Sequence

#: Every message type the stack publishes, subscribes to or needs for parameters and /tf.
USED_MESSAGE_TYPES = (
    'builtin_interfaces/msg/Time',
    'builtin_interfaces/msg/Duration',
    'std_msgs/msg/Header',
    'std_msgs/msg/String',
    'std_msgs/msg/Float64',
    'std_msgs/msg/Float64MultiArray',
    'geometry_msgs/msg/Point',
    'geometry_msgs/msg/Quaternion',
    'geometry_msgs/msg/Pose',
    'geometry_msgs/msg/PoseStamped',
    'geometry_msgs/msg/Vector3',
    'geometry_msgs/msg/Wrench',
    'geometry_msgs/msg/WrenchStamped',
    'geometry_msgs/msg/Twist',
    'geometry_msgs/msg/TwistWithCovariance',
    'geometry_msgs/msg/PoseWithCovariance',
    'geometry_msgs/msg/Transform',
    'geometry_msgs/msg/TransformStamped',
    'sensor_msgs/msg/JointState',
    'nav_msgs/msg/Odometry',
    'rosgraph_msgs/msg/Clock',
    'tf2_msgs/msg/TFMessage',
    'rcl_interfaces/msg/ParameterDescriptor',
    'rcl_interfaces/msg/FloatingPointRange',
    'rcl_interfaces/msg/IntegerRange',
    'rcl_interfaces/msg/SetParametersResult',
    'rcl_interfaces/msg/ParameterValue',
    'rcl_interfaces/msg/Parameter',
    'uvms_msgs/msg/ActuatorCommand',
    'uvms_msgs/msg/ContactState',
    'uvms_msgs/msg/ControllerState',
    'uvms_msgs/msg/GeneralizedForce',
    'uvms_msgs/msg/ThrusterState',
)

#: Python distributions whose versions the report shows; all are needed to run the stack.
DISTRIBUTIONS = ('numpy', 'scipy', 'rosbags', 'mcap', 'PyYAML')


@dataclass
class Runtime:
    """Which rclpy `import rclpy` gives."""

    kind: str
    path: str
    notes: list[str] = field(default_factory=list)


def detect_runtime() -> Runtime:
    """Find the active rclpy: a sourced ROS 2 wins; else ros2_compat (activated if needed)."""
    notes: list[str] = []
    try:
        import ros2_compat
    except ImportError:
        ros2_compat = None  # type: ignore[assignment]
    if importlib.util.find_spec('rclpy') is None and ros2_compat is not None:
        ros2_compat.activate()
        notes.append('ros2_compat fallback finder was not registered; doctor activated it')
    spec = importlib.util.find_spec('rclpy')
    if spec is None:
        return Runtime('none', '', [*notes, 'no rclpy: neither ROS 2 nor ros2_compat'])
    locations = list(spec.submodule_search_locations or [])
    path = spec.origin or (locations[0] if locations else '?')
    if ros2_compat is not None and _is_compat(ros2_compat, locations):
        if os.environ.get('ROS_DISTRO'):
            notes.append('ROS_DISTRO is set but rclpy is not importable from that install')
        return Runtime('ros2_compat', path, notes)
    distro = os.environ.get('ROS_DISTRO', '')
    if distro != 'jazzy':
        notes.append(f'this stack targets ROS 2 Jazzy; ROS_DISTRO is {distro or "unset"!r}')
    return Runtime('ros2', path, notes)


def _is_compat(ros2_compat: Any, locations: list[str]) -> bool:
    """Tell whether rclpy is ros2_compat's (its package directory inside the overlay)."""
    if ros2_compat.rclpy_is_compat():
        return True
    overlay = Path(ros2_compat.OVERLAY_DIR)
    return any(Path(location).resolve().is_relative_to(overlay) for location in locations)


def _load_class(typename: str) -> type:
    """Import the class of 'pkg/msg/Type' from its package, as node code does."""
    pkg, sub, name = typename.split('/')
    module = importlib.import_module(f'{pkg}.{sub}')
    cls = getattr(module, name)
    assert isinstance(cls, type)
    return cls


def _sample(cls: type) -> Any:
    """Return an instance with a few non-default values where the type has the fields."""
    msg = cls()
    fields = cls.get_fields_and_field_types()  # type: ignore[attr-defined]
    if fields.get('header') == 'std_msgs/Header':
        msg.header.frame_id = 'map_ned'
        msg.header.stamp.sec = 12
        msg.header.stamp.nanosec = 500_000_000
    for name, typ in fields.items():
        if typ == 'double':
            setattr(msg, name, 0.125)
        elif typ == 'sequence<double>':
            setattr(msg, name, [1.0, -2.5, 3.25])
        elif typ == 'sequence<string>':
            setattr(msg, name, ['joint_1', 'joint_2', 'joint_3'])
    return msg


def check_messages(types: Sequence[str]) -> tuple[list[tuple[str, str]], bool]:
    """Load, serialize and deserialize each type: ([(type, 'ok' or the error)], all ok)."""
    results: list[tuple[str, str]] = []
    try:
        from rclpy.serialization import deserialize_message, serialize_message
    except ImportError as exc:
        return [(typename, f'rclpy.serialization: {exc}') for typename in types], False
    all_ok = True
    for typename in types:
        try:
            cls = _load_class(typename)
            msg = _sample(cls)
            data = serialize_message(msg)
            if deserialize_message(data, cls) != msg:
                outcome = 'round trip changed the message'
            else:
                outcome = f'ok ({len(data)} bytes)'
        except Exception as exc:
            outcome = f'{type(exc).__name__}: {exc}'
        all_ok &= outcome.startswith('ok')
        results.append((typename, outcome))
    return results, all_ok


def _distribution_versions() -> tuple[list[tuple[str, str]], bool]:
    versions = []
    all_found = True
    for name in DISTRIBUTIONS:
        try:
            versions.append((name, importlib.metadata.version(name)))
        except importlib.metadata.PackageNotFoundError:
            versions.append((name, 'MISSING'))
            all_found = False
    return versions, all_found


def report(out: TextIO, types: Sequence[str] = USED_MESSAGE_TYPES) -> bool:
    """Write the doctor report to out and tell whether everything is in order."""
    runtime = detect_runtime()
    runtime_text = {
        'ros2': 'ROS 2 (real rclpy)',
        'ros2_compat': 'ros2_compat (in-process compatibility runtime, no ROS 2 sourced)',
        'none': 'NONE',
    }[runtime.kind]
    out.write('uvms doctor\n')
    out.write(f'  runtime     {runtime_text}\n')
    out.write(f'  rclpy       {runtime.path or "-"}\n')
    out.write(f'  ROS_DISTRO  {os.environ.get("ROS_DISTRO") or "(unset)"}\n')
    out.write(f'  python      {platform.python_version()} ({sys.executable})\n')
    versions, found = _distribution_versions()
    for name, version in versions:
        out.write(f'  {name:<11} {version}\n')
    for note in runtime.notes:
        out.write(f'  note: {note}\n')
    ok = found and runtime.kind != 'none'
    results, messages_ok = check_messages(types) if runtime.kind != 'none' else ([], False)
    out.write(f'messages: load, serialize, deserialize ({len(types)} types)\n')
    for typename, outcome in results:
        mark = 'ok  ' if outcome.startswith('ok') else 'FAIL'
        out.write(f'  {mark} {typename}: {outcome}\n')
    ok = ok and messages_ok
    out.write('all good\n' if ok else 'PROBLEMS FOUND (see above)\n')
    return ok


def main(argv: list[str] | None = None) -> int:
    """Print the report; return 0 when the runtime, dependencies and messages are all fine."""
    parser = argparse.ArgumentParser(
        prog='uvms doctor',
        description='Show the active ROS 2 runtime (real rclpy or ros2_compat) and check that '
        'every message type of the stack loads and round-trips through CDR.',
    )
    parser.parse_args(argv)
    return 0 if report(sys.stdout) else 1


if __name__ == '__main__':
    sys.exit(main())
