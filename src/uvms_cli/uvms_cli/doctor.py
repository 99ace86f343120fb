"""`uvms doctor`: which rclpy and rmw run, which DDS profile, and whether our messages work.

rclpy is the genuine one either way: Jazzy's PyPI wheels in the project venv, or a sourced
ROS 2 Jazzy install (which comes first on ``sys.path`` when sourced).
"""

from __future__ import annotations

import argparse
import importlib
import importlib.metadata
import os
import platform
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO

from uvms_common.ros_environment import network_summary, ros_environment_defaults

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
    'std_msgs/msg/ColorRGBA',
    'visualization_msgs/msg/Marker',
    'visualization_msgs/msg/MarkerArray',
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
    'uvms_msgs/msg/ContactTaskRecord',
    'uvms_msgs/msg/ControllerState',
    'uvms_msgs/msg/GeneralizedForce',
    'uvms_msgs/msg/ThrusterState',
)

#: Python distributions whose versions the report shows; all are needed to run the stack.
DISTRIBUTIONS = ('numpy', 'scipy', 'rosbags', 'mcap', 'PyYAML', 'matplotlib', 'foxglove-sdk')
#: Optional distributions, shown when installed: Ray runs ``uvms sweep`` (the sweep extra).
OPTIONAL_DISTRIBUTIONS = ('ray',)


@dataclass
class Runtime:
    """Which rclpy `import rclpy` gives, and on which middleware."""

    kind: str
    path: str
    version: str = ''
    rmw: str = ''
    notes: list[str] = field(default_factory=list)


def detect_runtime() -> Runtime:
    """Import rclpy (a sourced ROS 2 install's, or the venv's Jazzy wheels) and describe it."""
    try:
        import rclpy
        from rclpy.utilities import get_rmw_implementation_identifier
    except ImportError as exc:
        return Runtime('none', '', notes=[f'import rclpy failed: {exc}; run `make setup` or '
                                          'source ROS 2 Jazzy (README)'])
    path = str(Path(rclpy.__file__).resolve().parent)
    version = ''
    for distribution in ('ros-rclpy', 'ros-jazzy-rclpy', 'rclpy'):
        try:
            version = importlib.metadata.version(distribution)
            break
        except importlib.metadata.PackageNotFoundError:
            continue
    kind = 'wheels' if Path(sys.prefix) in Path(path).parents else 'sourced'
    try:
        rmw = get_rmw_implementation_identifier()
    except Exception as exc:  # rmw library missing or broken
        rmw = f'unavailable ({type(exc).__name__}: {exc})'
    return Runtime(kind, path, version, rmw)


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
            setattr(msg, name, ['first', 'second', 'third'])
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


def check_robots() -> tuple[list[tuple[str, str]], bool]:
    """Each robot folder and whether its files are all there: ([(name, outcome)], all ok)."""
    from uvms_description import robots_directory
    from uvms_description.robots import RobotFolderError, robot_files, robot_names

    try:
        names = robot_names()
        where = robots_directory()
    except FileNotFoundError as exc:
        return [('robots/', f'FileNotFoundError: {exc}')], False
    results: list[tuple[str, str]] = []
    for name in names:
        try:
            files = robot_files(name)
        except RobotFolderError as exc:
            results.append((name, str(exc)))
            continue
        results.append((name, f'ok ({files.urdf.relative_to(where)}, hydrodynamics and '
                              f'{len(files.parameter_files)} parameter files)'))
    return results, bool(results) and all(o.startswith('ok') for _, o in results)


def _distribution_versions() -> tuple[list[tuple[str, str]], bool]:
    versions = []
    all_found = True
    for name in DISTRIBUTIONS:
        try:
            versions.append((name, importlib.metadata.version(name)))
        except importlib.metadata.PackageNotFoundError:
            versions.append((name, 'MISSING'))
            all_found = False
    for name in OPTIONAL_DISTRIBUTIONS:
        try:
            versions.append((name, importlib.metadata.version(name)))
        except importlib.metadata.PackageNotFoundError:
            pass
    return versions, all_found


def realtime_lines() -> list[str]:
    """Whether a loop process may have SCHED_FIFO here (tried in a child), and the throttling.

    Informational: the graph runs without it, at normal priority (``uvms launch`` warns).
    """
    from uvms_common.scheduling import (
        DEFAULT_RT_PRIORITY,
        fifo_refusal,
        rtprio_limit,
        throttling,
    )

    refusal = fifo_refusal(DEFAULT_RT_PRIORITY)
    state = (f'available (SCHED_FIFO {DEFAULT_RT_PRIORITY} granted to a child; '
             f'RLIMIT_RTPRIO {rtprio_limit()})' if not refusal else f'NOT available: {refusal}')
    return [f'real time   {state}', f'rt throttle {throttling()}']


def report(out: TextIO, types: Sequence[str] = USED_MESSAGE_TYPES) -> bool:
    """Write the doctor report to out and tell whether everything is in order."""
    runtime = detect_runtime()
    runtime_text = {
        'wheels': 'ROS 2 Jazzy from PyPI wheels (genuine rclpy in this venv)',
        'sourced': 'ROS 2 from a sourced install (genuine rclpy)',
        'none': 'NONE',
    }[runtime.kind]
    out.write('uvms doctor\n')
    out.write(f'  runtime     {runtime_text}\n')
    out.write(f'  rclpy       {runtime.version or "?"} at {runtime.path or "-"}\n')
    out.write(f'  rmw         {runtime.rmw or "-"}\n')
    out.write(f'  ROS_DISTRO  {os.environ.get("ROS_DISTRO") or "(unset)"}\n')
    for line in network_summary():
        out.write(f'  {line}\n')
    out.write(f'  python      {platform.python_version()} ({sys.executable})\n')
    versions, found = _distribution_versions()
    for name, version in versions:
        out.write(f'  {name:<11} {version}\n')
    for line in realtime_lines():
        out.write(f'  {line}\n')
    for note in runtime.notes:
        out.write(f'  note: {note}\n')
    ok = found and runtime.kind != 'none'
    results, messages_ok = check_messages(types) if runtime.kind != 'none' else ([], False)
    out.write(f'messages: load, serialize, deserialize ({len(types)} types)\n')
    for typename, outcome in results:
        mark = 'ok  ' if outcome.startswith('ok') else 'FAIL'
        out.write(f'  {mark} {typename}: {outcome}\n')
    ok = ok and messages_ok
    robots, robots_ok = check_robots()
    out.write(f'robots: uvms_description robots/ ({len(robots)} found; --robot NAME)\n')
    for name, outcome in robots:
        mark = 'ok  ' if outcome.startswith('ok') else 'FAIL'
        out.write(f'  {mark} {name}: {outcome}\n')
    ok = ok and robots_ok
    out.write('all good\n' if ok else 'PROBLEMS FOUND (see above)\n')
    return ok


def main(argv: list[str] | None = None) -> int:
    """Print the report; return 0 when the runtime, dependencies and messages are all fine."""
    parser = argparse.ArgumentParser(
        prog='uvms doctor',
        description='Show which rclpy and rmw run, the DDS profile in force, and check that '
        'every message type of the stack loads and round-trips through CDR.',
    )
    parser.parse_args(argv)
    ros_environment_defaults()
    return 0 if report(sys.stdout) else 1


if __name__ == '__main__':
    sys.exit(main())
