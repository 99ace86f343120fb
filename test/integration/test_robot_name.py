"""robot_name on the real nodes: the robot's files become defaults; a bad robot stops start-up."""

from __future__ import annotations

import shutil
import signal
import subprocess
import sys
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest
import rclpy
from rclpy.context import Context
from rclpy.parameter import Parameter
from uvms_common.robot_parameters import RobotParameterError
from uvms_thrusters.thruster_allocator_node import ThrusterAllocatorNode

import uvms_description

PAPER = uvms_description.robots_directory() / 'paper_uvms'
BIN = Path(sys.executable).parent
SCENARIOS = Path(__file__).resolve().parents[2] / 'config' / 'scenarios'


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


def _uvms_run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(BIN / 'uvms'), 'run', *args], capture_output=True, text=True,
                          timeout=300, check=False)


def test_readme_bluerov_idle_wall_runs_at_the_robots_default_start() -> None:
    """``uvms run config/scenarios/idle_wall.yaml --robot bluerov2_alpha5`` runs (README)."""
    result = _uvms_run(str(SCENARIOS / 'idle_wall.yaml'), '--robot', 'bluerov2_alpha5',
                       '--duration', '0.2')
    assert result.returncode == 0, result.stderr[-2000:]
    assert 'simulated 0.20 s' in result.stderr


def test_failed_node_start_says_why_once_without_rosout_warning(tmp_path: Path) -> None:
    """A start out of reach: one error naming robot and default, no duplicate-rosout warning.

    The scenario check builds the simulator with the override, then without it: the first
    node, whose constructor raised, must be gone before the second is built.
    """
    scenario = tmp_path / 'far.yaml'
    scenario.write_text('name: far\ndescription: point A of the paper robot, on the BlueROV2\n'
                        'duration_s: 1.0\nseed: 1\nrobot: bluerov2_alpha5\nsimulator:\n'
                        '  initial:\n    ee_position: [1.70, 0.0, -0.10]\n')
    result = _uvms_run(str(scenario))
    assert result.returncode != 0
    assert 'Publisher already registered' not in result.stderr
    assert "robot 'bluerov2_alpha5': parameter 'initial.ee_position'" in result.stderr
    assert 'initial.ee_position = [0.37, 0.0, -0.07]' in result.stderr


def test_readme_bluerov_simulator_command_starts() -> None:
    """README: ``simulator --ros-args ... -p robot_name:=bluerov2_alpha5`` starts and waits."""
    config = SCENARIOS.parent
    command = [str(BIN / 'simulator'), '--ros-args', '-r', '__ns:=/uvms', '--params-file',
               str(config / 'robot.yaml'), '-p', 'robot_name:=bluerov2_alpha5']
    with subprocess.Popen(command, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL,
                          text=True) as process:
        watchdog = threading.Timer(120.0, process.kill)  # a hang fails below, never blocks
        watchdog.start()
        lines = []
        try:
            assert process.stderr is not None
            for line in process.stderr:
                lines.append(line)
                if 'waiting for the first actuator command' in line:
                    break
        finally:
            watchdog.cancel()
            process.send_signal(signal.SIGINT)
            process.wait(timeout=30)
    text = ''.join(lines)
    assert 'waiting for the first actuator command' in text, text[-2000:]
    assert 'FATAL' not in text
