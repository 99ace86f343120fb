"""Tests of the controller and allocator parameter validation."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from uvms_control.core.errors import ControlParameterError
from uvms_control.core.parameter_specs import (
    CONTROLLER_NODE_PARAMETER_SPECS,
    CONTROLLER_PARAMETER_SPECS,
    SAFETY_PARAMETER_SPECS,
)
from uvms_control.core.parameters import ControllerParameters, spd_matrix, validate_node_parameters
from uvms_control.core.task.contact_task import (
    ContactTaskGoal,
    SafetyLimits,
    TaskGoalError,
    validate_goal,
)
from uvms_thrusters.parameter_specs import ALLOCATOR_PARAMETER_SPECS
from uvms_thrusters.parameters import thruster_parameters_from_flat_dict


def test_defaults_are_valid() -> None:
    """The documented defaults build a controller configuration without error."""
    params = ControllerParameters.from_flat_dict()
    assert params.switch_mode == 'fuzzy'
    assert params.null_space_enabled
    np.testing.assert_allclose(params.force_direction, [1.0, 0.0, 0.0])


@pytest.mark.parametrize(
    ('name', 'value'),
    [
        ('impedance.inertia_kg', [50.0, -1.0, 50.0]),
        ('impedance.damping_n_s_m', [1.0, 2.0, 3.0, 2.0, 1.0, 0.0, 3.0, 0.0, 1.0]),
        ('impedance.stiffness_n_m', [0.0, 3000.0, 3000.0]),
        ('hybrid.position_kp', [1.0, 2.0]),
        ('hybrid.position_kd', [1.0, 0.5, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]),
    ],
)
def test_non_positive_definite_gain_matrix_names_the_parameter(
    name: str, value: list[float]
) -> None:
    """P, B_d, K, K_pp, K_pv that are not SPD stop start-up, naming parameter and range."""
    with pytest.raises(ControlParameterError, match=re.escape(name)) as info:
        ControllerParameters.from_flat_dict({name: value})
    assert 'positive-definite' in str(info.value)
    assert str(value[0]) in str(info.value)


@pytest.mark.parametrize('name', ['hybrid.force_kp', 'hybrid.force_ki', 'hybrid.force_kd'])
def test_negative_force_gain_names_the_parameter_and_range(name: str) -> None:
    """A negative PID gain is rejected with the parameter, its value and the valid range."""
    with pytest.raises(ControlParameterError, match=re.escape(name)) as info:
        ControllerParameters.from_flat_dict({name: -0.01})
    assert '-0.01' in str(info.value)
    assert '[0.0, 1000.0]' in str(info.value)


def test_full_symmetric_matrix_is_accepted() -> None:
    """Nine row-major entries of an SPD matrix give that matrix."""
    full = [2.0, 0.5, 0.0, 0.5, 2.0, 0.0, 0.0, 0.0, 1.0]
    params = ControllerParameters.from_flat_dict({'impedance.stiffness_n_m': full})
    np.testing.assert_allclose(params.impedance_stiffness, np.reshape(full, (3, 3)))


def test_spd_matrix_from_diagonal_is_diagonal() -> None:
    """Three entries are the diagonal of the matrix."""
    np.testing.assert_allclose(spd_matrix('x', [1.0, 2.0, 3.0]), np.diag([1.0, 2.0, 3.0]))


@pytest.mark.parametrize(
    ('name', 'value'),
    [
        ('model.mass_scale', 0.0),
        ('force.contact_threshold_n', math.nan),
        ('hybrid.force_integral_limit_n_s', -0.1),
        ('mode', 'adaptive'),
        ('null_space.stiffness_1_s2', [1.0] * 8),
        ('fuzzy.force_ratio_medium', [0.5, 0.1, 0.9]),
        ('hybrid.force_direction', [0.0, 0.0, 0.0]),
    ],
)
def test_invalid_values_name_the_parameter(name: str, value: object) -> None:
    """Out-of-range, malformed or unknown-choice values raise naming the parameter."""
    with pytest.raises(ControlParameterError, match=re.escape(name)):
        ControllerParameters.from_flat_dict({name: value})


def test_unknown_parameter_is_rejected() -> None:
    """A misspelled name is an error rather than silently ignored."""
    with pytest.raises(ControlParameterError, match=r'impedance\.stifness'):
        ControllerParameters.from_flat_dict({'impedance.stifness': [1.0, 1.0, 1.0]})


@pytest.mark.parametrize('force_n', [200.0, 150.0])
def test_goal_force_at_or_below_the_contact_threshold_is_refused(force_n: float) -> None:
    """A task force at or below the contact threshold could never start a force ramp."""
    params = ControllerParameters.from_flat_dict({'force.contact_threshold_n': 200.0})
    goal = ContactTaskGoal(
        path=np.array([[1.7, 0.0, 0.0], [1.8, 0.0, 0.0]]),
        times=np.array([0.0, 2.0]),
        velocities=None,
        accelerations=None,
        normal=np.array([1.0, 0.0, 0.0]),
        force_n=force_n,
        force_ramp_s=1.0,
    )
    with pytest.raises(TaskGoalError, match=r'^force_n = .*contact threshold') as info:
        validate_goal(goal, np.array([1.7, 0.0, 0.0]), SafetyLimits(), params.contact_threshold)
    assert info.value.field == 'force_n'


def test_unknown_trigger_mode_is_rejected() -> None:
    """trigger_mode must be lockstep or timer."""
    with pytest.raises(ControlParameterError, match='trigger_mode'):
        validate_node_parameters(CONTROLLER_NODE_PARAMETER_SPECS, {'trigger_mode': 'sometimes'})


def test_thruster_parameters_use_the_given_water_density() -> None:
    """ρ comes from the robot's hydrodynamics parameters, the rest from thruster.* names."""
    params = thruster_parameters_from_flat_dict({'thruster.propeller_diameter_m': 0.2}, 1000.0)
    assert (params.water_density, params.propeller_diameter) == (1000.0, 0.2)


@pytest.mark.parametrize(
    'specs',
    [
        CONTROLLER_PARAMETER_SPECS,
        CONTROLLER_NODE_PARAMETER_SPECS,
        SAFETY_PARAMETER_SPECS,
        ALLOCATOR_PARAMETER_SPECS,
    ],
)
def test_every_parameter_is_documented_with_a_unit_or_choice(specs: list) -> None:  # type: ignore[type-arg]
    """Each spec states a unit in parentheses (or its choices), and its default is in range."""
    names = [spec.name for spec in specs]
    assert len(names) == len(set(names))
    for spec in specs:
        assert '(' in spec.description or "'" in spec.description, spec.name
        values = spec.default if isinstance(spec.default, list) else [spec.default]
        for value in values:
            if isinstance(value, float):
                assert spec.min_value is None or value >= spec.min_value, spec.name
                assert spec.max_value is None or value <= spec.max_value, spec.name
