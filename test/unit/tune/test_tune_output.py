"""The tuned gains file: a ROS 2 parameter file the controller's specs and rcl both accept."""

from __future__ import annotations

from pathlib import Path

import pytest
import rclpy
from rclpy.node import Node
from uvms_tune.control_api import ControllerParameters
from uvms_tune.gains import controller_values, hand_tuned
from uvms_tune.output import ROBOT_TUNED_FILE, apply_to_robot, read_gains, write_gains

from uvms_description.robots import parameter_file_values

VALUES = controller_values({'impedance.natural_frequency_rad_s': 9.0,
                            'impedance.damping_ratio': 0.8, 'hybrid.force_kp': 0.07},
                           hand_tuned('bluerov2_alpha5'))
PROVENANCE = {'robot': 'bluerov2_alpha5', 'tune_file': 't.yaml', 'trial': 4, 'trials': 9,
              'objective': 0.12, 'stability_margin': 0.002, 'commit': 'abc',
              'figures': [{'label': 'run#0/seed1', 'force_rms_error_N': 0.5,
                           'overshoot_percent': 3.0, 'settling_time_s': None}]}


@pytest.fixture
def gains_file(tmp_path: Path) -> Path:
    """The file as ``uvms tune`` writes it."""
    return write_gains(tmp_path, VALUES, PROVENANCE)


def test_written_gains_read_back_equal(gains_file: Path) -> None:
    """Write then read: the same flat parameters."""
    read = read_gains(gains_file)
    assert read.keys() == VALUES.keys()
    for key, value in VALUES.items():
        assert read[key] == pytest.approx(value)


def test_written_gains_pass_the_controller_parameter_specs(gains_file: Path) -> None:
    """Read as a robot parameter file, over the hand-tuned gains, they validate."""
    values = {key: item.value for key, item in
              parameter_file_values(gains_file, 'controller').items()}
    params = ControllerParameters.from_flat_dict({**hand_tuned('bluerov2_alpha5'), **values})
    assert params.force_kp == pytest.approx(0.07)
    assert params.impedance_stiffness[0, 0] == pytest.approx(50.0 * 81.0)


def test_rcl_loads_the_file_into_a_controller_node(gains_file: Path) -> None:
    """``--ros-args --params-file`` gives a node named controller the tuned values."""
    context = rclpy.Context()
    rclpy.init(args=['--ros-args', '--params-file', str(gains_file)], context=context)
    try:
        node = Node('controller', context=context,
                    automatically_declare_parameters_from_overrides=True)
        try:
            assert node.get_parameter('hybrid.force_kp').value == pytest.approx(0.07)
            assert list(node.get_parameter('impedance.stiffness_n_m').value) == pytest.approx(
                VALUES['impedance.stiffness_n_m'])
        finally:
            node.destroy_node()
    finally:
        rclpy.shutdown(context=context)


def test_apply_writes_beside_the_hand_tuned_file(gains_file: Path, tmp_path: Path) -> None:
    """--apply writes controller_tuned.yaml and leaves controller.yaml as it was."""
    robot = tmp_path / 'robot'
    robot.mkdir()
    (robot / 'controller.yaml').write_text('hand', encoding='utf-8')
    target = apply_to_robot(gains_file, robot)
    assert target.name == ROBOT_TUNED_FILE
    assert (robot / 'controller.yaml').read_text(encoding='utf-8') == 'hand'
    assert read_gains(target) == read_gains(gains_file)
