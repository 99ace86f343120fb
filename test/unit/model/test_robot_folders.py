"""Robot folders: found by name or path, each file required, bad input named in one line."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml
from uvms_bringup.launch_helpers import file_parameters
from uvms_common.robot_parameters import with_robot_source

import uvms_description
from uvms_description.robots import (
    RobotFolderError,
    parameter_file_values,
    robot_files,
    robot_names,
    robot_parameters,
    urdf_text,
)
from uvms_model import ParameterError, UvmsModel, UvmsParameters, load_description

PAPER = uvms_description.robots_directory() / 'paper_uvms'


@pytest.fixture
def robot(tmp_path: Path) -> Path:
    """A copy of the paper's robot folder, named ``mine``, to break."""
    folder = tmp_path / 'robots' / 'mine'
    shutil.copytree(PAPER, folder)
    return folder


def test_paper_robot_is_found_by_name_with_its_six_files() -> None:
    """robots/paper_uvms holds robot.urdf, hydrodynamics.yaml and the four parameter files."""
    assert 'paper_uvms' in robot_names()
    files = robot_files('paper_uvms')
    assert files.urdf.name == 'robot.urdf'
    assert [p.name for p in files.parameter_files] == [
        'thrusters.yaml', 'sensor.yaml', 'controller.yaml', 'navigation.yaml', 'start.yaml']


def test_unknown_robot_lists_the_known_ones(robot: Path) -> None:
    """An unknown name stops with the robots that exist."""
    with pytest.raises(RobotFolderError, match=r"unknown robot 'nope': the robots in .* are mine"):
        robot_files('nope', robot.parent)


@pytest.mark.parametrize('missing', ['robot.urdf', 'hydrodynamics.yaml', 'thrusters.yaml',
                                     'sensor.yaml', 'controller.yaml', 'navigation.yaml',
                                     'start.yaml'])
def test_missing_file_is_named(robot: Path, missing: str) -> None:
    """A folder without one of its files names the folder and the file."""
    (robot / missing).unlink()
    pattern = 'neither robot.urdf nor robot.urdf.xacro' if missing == 'robot.urdf' else (
        rf'mine/{missing}: missing file of robot')
    with pytest.raises(RobotFolderError, match=pattern) as error:
        robot_files('mine', robot.parent)
    assert '\n' not in str(error.value)


def test_robot_is_found_by_path(robot: Path) -> None:
    """A name with a '/' is a folder anywhere."""
    assert robot_files(str(robot)).directory == robot


def test_xacro_is_expanded_at_load(robot: Path) -> None:
    """robot.urdf.xacro with a property gives the same model as the plain URDF."""
    text = (robot / 'robot.urdf').read_text()
    text = text.replace('<robot name="uvms">',
                        '<robot name="uvms" xmlns:xacro="http://www.ros.org/wiki/xacro">'
                        '<xacro:property name="hull_mass" value="530.0"/>')
    text = text.replace('<mass value="530.0"/>', '<mass value="${hull_mass}"/>')
    (robot / 'robot.urdf').unlink()
    (robot / 'robot.urdf.xacro').write_text(text)
    files = robot_files('mine', robot.parent)
    assert '${' not in urdf_text(files.urdf)
    description = load_description(files.urdf, files.hydrodynamics)
    model = UvmsModel(description=description)
    reference = UvmsModel()
    q = np.array([0.1, -0.2, 0.3, 0.1, 0.2, -0.3, 0.2, 0.5, -0.9])
    np.testing.assert_array_equal(model.mass_matrix_body(q), reference.mass_matrix_body(q))


def test_xacro_error_names_the_file(robot: Path) -> None:
    """An undefined xacro property stops with the file in one line."""
    (robot / 'robot.urdf').unlink()
    (robot / 'robot.urdf.xacro').write_text(
        '<robot name="x" xmlns:xacro="http://www.ros.org/wiki/xacro"><link name="${nope}"/>'
        '</robot>')
    files = robot_files('mine', robot.parent)
    with pytest.raises(RobotFolderError, match=r'robot\.urdf\.xacro: xacro expansion failed') as e:
        urdf_text(files.urdf)
    assert '\n' not in str(e.value)


def test_parameter_files_give_node_sections_and_common_ones() -> None:
    """/** reaches every node, /**/thruster_allocator only the allocator."""
    allocator = robot_parameters('paper_uvms', 'thruster_allocator')
    simulator = robot_parameters('paper_uvms', 'simulator')
    assert allocator['thrusters.max_thrust_n'].value == [200.0] * 8
    assert allocator['allocator.max_joint_torque_n_m'].value == [200.0] * 3
    assert 'allocator.max_joint_torque_n_m' not in simulator
    assert simulator['sensor.force_range_n'].source.name == 'sensor.yaml'


def test_bad_section_of_a_parameter_file_is_named(robot: Path) -> None:
    """A section that is neither /** nor /**/<node> names the file and the section."""
    (robot / 'sensor.yaml').write_text('controller:\n  ros__parameters: {a: 1}\n')
    with pytest.raises(RobotFolderError, match=r"sensor\.yaml: section 'controller'"):
        parameter_file_values(robot / 'sensor.yaml', 'controller')


def test_parameter_given_twice_is_refused(robot: Path) -> None:
    """Two robot files giving one parameter: the second file is named."""
    (robot / 'sensor.yaml').write_text(
        '/**:\n  ros__parameters:\n    thrusters:\n      max_thrust_n: [1.0]\n')
    with pytest.raises(RobotFolderError, match=r"sensor\.yaml: parameter 'thrusters.max_thrust_n' "
                                               r'is also given by .*thrusters\.yaml'):
        robot_parameters('mine', 'simulator', robot.parent)


def test_rank_deficient_thrusters_name_the_robot_file(robot: Path) -> None:
    """Thrusters that cannot roll (all in one line): the error names thrusters.yaml."""
    values = {name: item for name, item in robot_parameters('mine', 'simulator',
                                                             robot.parent).items()}
    flat = {name: item.value for name, item in values.items()
            if not name.startswith(('initial.', 'navigation.'))}  # the simulator's own
    flat['thrusters.positions_m'] = [float(v) for i in range(8) for v in (0.1 * i, 0.0, 0.0)]
    flat['thrusters.directions'] = [1.0, 0.0, 0.0] * 8
    with pytest.raises(ParameterError, match='rank') as error:
        UvmsParameters.from_flat_dict(flat)
    message = with_robot_source(str(error.value), values)
    assert message.startswith(str(robot / 'thrusters.yaml') + ': ')
    assert '\n' not in message


def test_hydrodynamics_entry_for_a_link_the_urdf_lacks_is_named(robot: Path) -> None:
    """A link in hydrodynamics.yaml that is not in the URDF: file and link named."""
    tree = yaml.safe_load((robot / 'hydrodynamics.yaml').read_text())
    tree['link_9'] = tree['link_3']
    (robot / 'hydrodynamics.yaml').write_text(yaml.safe_dump(tree))
    files = robot_files('mine', robot.parent)
    with pytest.raises(ValueError, match=r"hydrodynamics\.yaml: links \['link_9'\] are not"):
        load_description(files.urdf, files.hydrodynamics)


@pytest.mark.parametrize('node', ['simulator', 'controller', 'thruster_allocator'])
def test_config_files_hold_no_robot_parameter(node: str) -> None:
    """config/robot.yaml and config/controller.yaml would override every robot's values."""
    config = Path(__file__).resolve().parents[3] / 'config'
    given = set(file_parameters(config / 'robot.yaml', node, 'uvms'))
    given |= set(file_parameters(config / 'controller.yaml', node, 'uvms'))
    for name in robot_names():
        assert not given & set(robot_parameters(name, node)), name
