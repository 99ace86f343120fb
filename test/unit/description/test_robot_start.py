"""Robot default starts: every robot folder's start.yaml fits its arm; the paper's stays at A."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from uvms_scenarios.scenario import load_scenario
from uvms_sim.errors import SimParameterError
from uvms_sim.parameters import default_joint_positions
from uvms_sim.plant import initial_coordinates

import uvms_description
from uvms_description.robots import (
    RobotFolderError,
    robot_files,
    robot_names,
    robot_parameters,
    robot_start,
    with_description_paths,
)
from uvms_model import UvmsModel, UvmsParameters

ROOT = Path(__file__).resolve().parents[3]
PAPER = uvms_description.robots_directory() / 'paper_uvms'
#: The paper robot's start before robots carried one (the simulator's built-in defaults, and
#: what every paper scenario sets): point A of Fig. 7, the vehicle at the origin.
PAPER_START = {
    'initial.vehicle_pose': [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    'initial.arm': 'ee_position',
    'initial.ee_position': [1.70, 0.0, -0.10],
    'initial.joint_positions': [0.0, 0.4, -0.8],
}


def _model(name: str) -> UvmsModel:
    flat = {key: item.value for key, item in robot_parameters(name, 'simulator').items()
            if not key.startswith(('initial.', 'navigation.', 'devices.'))}
    return UvmsModel(UvmsParameters.from_flat_dict(with_description_paths(flat, name)))


@pytest.mark.parametrize('name', robot_names())
def test_every_robot_starts_where_its_default_start_puts_it(name: str) -> None:
    """start.yaml: all four initial.* keys, and the arm reaches its ee_position."""
    start = robot_start(name)
    assert set(start) == set(PAPER_START)
    model = _model(name)
    guess = default_joint_positions(np.array(start['initial.joint_positions'], float),
                                    model.n_joints)
    assert guess.shape == (model.n_joints,)
    q0 = initial_coordinates(model, start['initial.vehicle_pose'], guess,
                             start['initial.ee_position'])
    np.testing.assert_allclose(model.ee_position(q0), start['initial.ee_position'], atol=1e-6)


def test_paper_robot_start_is_point_a_as_before() -> None:
    """The paper robot's default start is exactly the start its scenarios always had."""
    assert robot_start('paper_uvms') == PAPER_START


PAPER_SCENARIOS = [path for path in sorted((ROOT / 'config' / 'scenarios').glob('*.yaml'))
                   if load_scenario(path).robot in (None, 'paper_uvms')]


@pytest.mark.parametrize('path', PAPER_SCENARIOS, ids=lambda p: p.stem)
def test_paper_scenarios_start_at_point_a(path: Path) -> None:
    """Every paper-robot scenario starts at A: by its own initial.* or by the robot's default."""
    scenario = load_scenario(path)
    simulator = scenario.overrides.get('simulator', {})
    effective = {**robot_start('paper_uvms'),
                 **{k: v for k, v in simulator.items() if k.startswith('initial.')}}
    assert effective == PAPER_START


def test_bluerov_default_start_is_reachable_where_the_paper_point_is_not() -> None:
    """The BlueROV2's arm cannot reach the paper's point A; its own start is in reach."""
    model = _model('bluerov2_alpha5')
    start = robot_start('bluerov2_alpha5')
    with pytest.raises(SimParameterError) as error:
        initial_coordinates(model, np.zeros(6), start['initial.joint_positions'],
                            PAPER_START['initial.ee_position'], 'bluerov2_alpha5', start)
    message = str(error.value)
    assert message.startswith("robot 'bluerov2_alpha5': parameter 'initial.ee_position' = "
                              '[1.7, 0.0, -0.1]: out of reach')
    assert 'residual 1.4' in message
    assert 'default start (its start.yaml' in message
    assert 'initial.ee_position = [0.37, 0.0, -0.07]' in message
    assert '\n' not in message


@pytest.fixture
def robot(tmp_path: Path) -> Path:
    """A copy of the paper's robot folder, named ``mine``, to break."""
    folder = tmp_path / 'robots' / 'mine'
    shutil.copytree(PAPER, folder)
    return folder


def test_robot_without_start_file_is_refused_naming_it(robot: Path) -> None:
    """start.yaml is one of the required files."""
    (robot / 'start.yaml').unlink()
    with pytest.raises(RobotFolderError, match=r'mine/start\.yaml: missing file of robot'):
        robot_files('mine', robot.parent)


def test_start_parameter_outside_start_file_is_refused(robot: Path) -> None:
    """initial.* in sensor.yaml: the file and the key named, start.yaml named as its place."""
    (robot / 'sensor.yaml').write_text(
        '/**/simulator:\n  ros__parameters:\n    initial:\n      arm: joint_positions\n')
    with pytest.raises(RobotFolderError, match=r"sensor\.yaml: parameter 'initial\.arm': the "
                                               r'start parameters .* belong in start\.yaml'):
        robot_parameters('mine', 'simulator', robot.parent)


def test_other_parameter_in_start_file_is_refused(robot: Path) -> None:
    """A gain in start.yaml is refused: the file holds the start only."""
    (robot / 'start.yaml').write_text(
        '/**/simulator:\n  ros__parameters:\n    sensor:\n      cutoff_hz: 3.0\n')
    with pytest.raises(RobotFolderError, match=r"start\.yaml: parameter 'sensor\.cutoff_hz'"):
        robot_parameters('mine', 'simulator', robot.parent)
