"""The actuators' terms written where the robot folder takes them: thrusters.yaml, robot.urdf."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from uvms_identify.actuator_output import MODEL_TIME_CONSTANT_S, write_thrusters, write_urdf
from uvms_identify.actuators import Term, ThrustPath
from uvms_identify.identify import Identification
from uvms_identify.robot_data import load_robot
from uvms_model.description import load_description

from uvms_description.robots import parameter_file_values

ROBOT = 'bluerov2_alpha5'


def _result(lag_s: float, lag_status: str, friction: list[Term]) -> Identification:
    robot = load_robot(ROBOT)
    path = ThrustPath(Term('thrust_gain', 0.9, 0.02, 'well determined', '-'),
                      Term('thrust_time_constant_s', lag_s, 0.01, lag_status, 's'), 0.01,
                      np.ones(6))
    fit: Any = None
    return Identification(robot, [], fit, robot.prior_theta(), [], [], delay_s=0.01,
                          thrust=path, joint_friction=friction)


def _inertia(path: Path) -> float:
    values = parameter_file_values(path, 'thruster_allocator')
    return float(values['thruster.motor_inertia_kg_m2'].value)


def test_an_identified_lag_slows_the_thrusters_motor_in_proportion(tmp_path: Path) -> None:
    """40 ms more lag than the model's 20 ms: J_m x3; the file stays a parameter file."""
    result = _result(0.04, 'well determined', [])
    shipped = _inertia(result.robot.files.directory / 'thrusters.yaml')
    path = write_thrusters(result, tmp_path, ['# provenance'])
    factor = (MODEL_TIME_CONSTANT_S + 0.04) / MODEL_TIME_CONSTANT_S
    assert _inertia(path) == pytest.approx(shipped * factor, rel=1e-3)
    text = path.read_text(encoding='utf-8')
    assert 'thrust_gain = 0.9 +- 0.02' in text and 'ardusub.t200' in text
    (tmp_path / 'none').mkdir()
    unchanged = write_thrusters(_result(0.0, 'unidentifiable: ...', []), tmp_path / 'none', [])
    assert _inertia(unchanged) == pytest.approx(shipped)


def test_identified_joint_friction_goes_into_the_urdf_the_model_still_loads(
        tmp_path: Path) -> None:
    """<dynamics damping friction> on the joints identified, none on those not."""
    friction = [Term('joint_1_viscous_friction_n_m_s', 2.4, 0.1, 'well determined', ''),
                Term('joint_1_coulomb_friction_n_m', 0.3, 0.02, 'well determined', ''),
                Term('joint_2_viscous_friction_n_m_s', 0.0, 1.0, 'unidentifiable: x', ''),
                Term('joint_2_coulomb_friction_n_m', 0.0, 1.0, 'unidentifiable: x', '')]
    result = _result(0.0, 'unidentifiable: ...', friction)
    path = write_urdf(result, tmp_path, ['# provenance'])
    assert path is not None
    text = path.read_text(encoding='utf-8')
    joint_1 = text[text.index('<joint name="joint_1"'):]
    assert '<dynamics damping="2.4" friction="0.3"/>' in joint_1[:joint_1.index('</joint>')]
    assert text.count('<dynamics damping="') == 1
    description = load_description(path, result.robot.files.hydrodynamics)
    assert description.joint_names[0] == 'joint_1'
    assert write_urdf(_result(0.0, 'x', friction[2:]), tmp_path, []) is None
