"""robot_name on the real nodes: the robot's files become defaults; a bad robot stops start-up."""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from pathlib import Path

import pytest
import rclpy
from rclpy.context import Context
from rclpy.parameter import Parameter
from uvms_common.robot_parameters import RobotParameterError
from uvms_control.thruster_allocator_node import ThrusterAllocatorNode

import uvms_description

PAPER = uvms_description.robots_directory() / 'paper_uvms'


@pytest.fixture
def context() -> Iterator[Context]:
    """A private rclpy context."""
    ctx = Context()
    rclpy.init(args=[], context=ctx)
    yield ctx
    rclpy.try_shutdown(context=ctx)


def _allocator(context: Context, robot: str) -> ThrusterAllocatorNode:
    return ThrusterAllocatorNode(context=context, parameter_overrides=[
        Parameter('robot_name', value=robot), Parameter('autostart', value=False)])


def test_robot_files_are_the_node_defaults(context: Context, tmp_path: Path) -> None:
    """A robot folder given by path: its thrusters.yaml values are the allocator's parameters."""
    folder = tmp_path / 'mine'
    shutil.copytree(PAPER, folder)
    text = (folder / 'thrusters.yaml').read_text()
    limits = '[' + ', '.join(['200.0'] * 8) + ']'
    assert limits in text
    lower = '[' + ', '.join(['150'] * 8) + ']'  # integers: taken as floats
    (folder / 'thrusters.yaml').write_text(text.replace(limits, lower))
    node = _allocator(context, str(folder))
    try:
        assert list(node.get_parameter('thrusters.max_thrust_n').value) == [150.0] * 8
        assert node.get_parameter('robot_name').value == str(folder)
    finally:
        node.destroy_node()


def test_unknown_robot_stops_start_up_listing_the_known_ones(context: Context) -> None:
    """robot_name 'nope': one line with the robots that exist."""
    with pytest.raises(RobotParameterError, match=r"unknown robot 'nope': .* paper_uvms") as e:
        _allocator(context, 'nope')
    assert '\n' not in str(e.value)


def test_misspelt_key_in_a_robot_file_stops_start_up_naming_the_file(
    context: Context, tmp_path: Path
) -> None:
    """A key no node declares (max_thrust instead of max_thrust_n) names the file."""
    folder = tmp_path / 'mine'
    shutil.copytree(PAPER, folder)
    text = (folder / 'thrusters.yaml').read_text().replace('max_thrust_n:', 'max_thrust:')
    (folder / 'thrusters.yaml').write_text(text)
    with pytest.raises(RobotParameterError, match=r"mine/thrusters\.yaml: parameter "
                                                  r"'thrusters\.max_thrust' is not a parameter"):
        _allocator(context, str(folder))
