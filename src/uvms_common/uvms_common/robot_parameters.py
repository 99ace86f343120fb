"""The ``robot_name`` parameter every node takes, and its robot's values as parameter defaults.

A node declares ``robot_name`` first (``declare_robot``), then declares its other parameters
with the robot's values (``uvms_description.robots.robot_parameters``) as defaults; what the
node is given by ``--params-file``, a scenario or ``-p`` still wins, as for any ROS default.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

from rcl_interfaces.msg import ParameterDescriptor
from rclpy.node import Node

from uvms_description import DEFAULT_ROBOT
from uvms_description.robots import (
    START_PREFIX,
    RobotFolderError,
    RobotParameter,
    robot_parameters,
    with_description_paths,
)

ROBOT_NAME_PARAMETER = 'robot_name'


class RobotParameterError(ValueError):
    """The robot named by ``robot_name`` cannot be loaded, or gives a parameter it should not."""


def declare_robot_name(node: Node) -> str:
    """Declare the read-only ``robot_name`` parameter and return its value."""
    descriptor = ParameterDescriptor(
        description=('Robot folder of uvms_description (robots/<name>/): URDF, '
                     'hydrodynamics, thrusters, wrist sensor, controller gains.'),
        read_only=True)
    if node.has_parameter(ROBOT_NAME_PARAMETER):
        return str(node.get_parameter(ROBOT_NAME_PARAMETER).value)
    return str(node.declare_parameter(ROBOT_NAME_PARAMETER, DEFAULT_ROBOT, descriptor).value)


def declare_robot(node: Node) -> tuple[str, dict[str, RobotParameter]]:
    """Declare ``robot_name`` and read its robot's parameter values for this node.

    Raises:
        RobotParameterError: An unknown robot or a bad robot folder (one line naming the
            file and the element).
    """
    name = declare_robot_name(node)
    try:
        return name, robot_parameters(name, node.get_name())
    except RobotFolderError as exc:
        raise RobotParameterError(str(exc)) from exc


def robot_default(values: Mapping[str, RobotParameter], name: str, default: Any) -> Any:
    """The robot's value of parameter ``name`` in the type of ``default``, else ``default``.

    YAML writes ``200`` for a float parameter; ROS would refuse an integer there, so numbers
    are converted to floats where the built-in default is a float (or a list of floats).
    """
    if name not in values:
        return default
    value = values[name].value
    if isinstance(default, float) and isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    if isinstance(default, list | tuple) and isinstance(value, list) and all(
            isinstance(v, int | float) and not isinstance(v, bool) for v in value) and all(
            isinstance(v, float) for v in default):
        return [float(v) for v in value]
    return value


def robot_start_values(values: Mapping[str, RobotParameter]) -> dict[str, Any]:
    """The robot's default start among its values: ``initial.*`` of its ``start.yaml``."""
    return {name: item.value for name, item in values.items() if name.startswith(START_PREFIX)}


def check_all_declared(node: Node, values: Mapping[str, RobotParameter],
                       ignored: Iterable[str] = ()) -> None:
    """Refuse a robot parameter this node does not declare (a misspelt key in a robot file).

    Raises:
        RobotParameterError: Naming the file and the parameter.
    """
    skip = set(ignored)
    for name, item in values.items():
        if name not in skip and not node.has_parameter(name):
            msg = (f'{item.source}: parameter {name!r} is not a parameter of the '
                   f'{node.get_name()} node')
            raise RobotParameterError(msg)


def robot_model_values(values: Mapping[str, Any], robot: str) -> dict[str, Any]:
    """A node's model parameter values with the robot's URDF and hydrodynamics paths filled in.

    Raises:
        RobotParameterError: The robot folder cannot be read.
    """
    try:
        return with_description_paths(values, robot)
    except RobotFolderError as exc:
        raise RobotParameterError(str(exc)) from exc


def with_robot_source(message: str, values: Mapping[str, RobotParameter]) -> str:
    """``message`` prefixed with the robot file that gave the parameter it names, if any.

    >>> from pathlib import Path
    >>> item = RobotParameter([1.0], Path('robots/mine/thrusters.yaml'))
    >>> with_robot_source("thrusters.directions: rank 5", {'thrusters.directions': item})
    'robots/mine/thrusters.yaml: thrusters.directions: rank 5'
    """
    for name, item in values.items():
        if name in message:
            return f'{item.source}: {message}'
    return message
