"""Validated parameters of the controller, checked against their specs.

Each ``*_PARAMETER_SPECS`` list of `uvms_control.core.parameter_specs` is the single source
of the names, defaults, units and ranges that the nodes declare (with descriptors) and that
``config/controller.yaml`` sets. The ``from_flat_dict`` constructors validate values and
raise `ControlParameterError` naming the parameter, the value and the valid range.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from uvms_common.parameter_spec import TRIGGER_MODES, ParameterSpec, merged_values

from uvms_control.core.errors import ControlParameterError
from uvms_control.core.fuzzy_sets import FuzzySwitchParameters, Trapezoid
from uvms_control.core.parameter_specs import (
    CONTROLLER_PARAMETER_SPECS,
    CONTROLLER_TRIGGER_MODES,
    STATE_SOURCES,
    SWITCH_MODES,
)

FloatArray = npt.NDArray[np.float64]


def _merged(specs: Sequence[ParameterSpec], values: Mapping[str, object]) -> dict[str, object]:
    """Defaults overridden by ``values``; unknown names and out-of-range numbers raise."""
    return merged_values(specs, values, ControlParameterError)


def spd_matrix(name: str, values: Sequence[float]) -> FloatArray:
    """3x3 symmetric positive-definite matrix from 3 diagonal or 9 row-major entries.

    Raises:
        ControlParameterError: naming the parameter, if the matrix is not SPD.
    """
    data = np.asarray(values, dtype=np.float64).reshape(-1)
    valid = 'a symmetric positive-definite 3x3 matrix: 3 diagonal entries > 0 or 9 row-major'
    if data.size == 3:
        matrix = np.diag(data)
    elif data.size == 9:
        matrix = data.reshape(3, 3)
    else:
        raise ControlParameterError(name, data.tolist(), valid)
    if not np.all(np.isfinite(matrix)) or not np.allclose(matrix, matrix.T, rtol=1e-9, atol=1e-12):
        raise ControlParameterError(name, data.tolist(), valid)
    if float(np.min(np.linalg.eigvalsh(matrix))) <= 0.0:
        raise ControlParameterError(name, data.tolist(), valid)
    return matrix


def _vector3(name: str, values: Sequence[float]) -> FloatArray:
    data = np.asarray(values, dtype=np.float64).reshape(-1)
    if data.size != 3:
        raise ControlParameterError(name, data.tolist(), '3 values')
    return data


def _unit3(name: str, values: Sequence[float]) -> FloatArray:
    data = _vector3(name, values)
    norm = float(np.linalg.norm(data))
    if norm < 1e-9:
        raise ControlParameterError(name, data.tolist(), 'a non-zero 3-vector')
    unit: FloatArray = data / norm
    return unit


def _membership(name: str, values: Sequence[float], shape: str) -> Trapezoid:
    data = [float(v) for v in values]
    try:
        if shape == 'left' and len(data) == 2:
            return Trapezoid.left_shoulder(data[0], data[1], name)
        if shape == 'right' and len(data) == 2:
            return Trapezoid.right_shoulder(data[0], data[1], name)
        if shape == 'inner' and len(data) == 3:
            return Trapezoid.triangle(data[0], data[1], data[2], name)
        if shape == 'inner' and len(data) == 4:
            return Trapezoid(data[0], data[1], data[2], data[3], name)
    except ControlParameterError:
        pass
    expected = {
        'left': '[full_until, zero_from] with full_until <= zero_from',
        'right': '[zero_until, full_from] with zero_until <= full_from',
        'inner': 'a triangle [left, peak, right] or trapezoid [a, b, c, d], non-decreasing',
    }[shape]
    raise ControlParameterError(name, data, expected)


@dataclass(frozen=True)
class ControllerParameters:
    """Validated gains and settings of the unified force controller (paper sec. 4).

    Build it with `from_flat_dict` (flat dotted names as in config/controller.yaml); the
    default-constructed value holds the documented defaults.
    """

    mass_scale: float
    impedance_inertia: FloatArray
    impedance_damping: FloatArray
    impedance_stiffness: FloatArray
    force_direction: FloatArray
    position_kp: FloatArray
    position_kd: FloatArray
    force_kp: float
    force_ki: float
    force_kd: float
    force_feedforward_compliance: float
    force_derivative_cutoff_hz: float
    force_integral_limit: float
    switch_mode: str
    fuzzy: FuzzySwitchParameters
    contact_threshold: float
    null_space_enabled: bool
    null_space_stiffness: FloatArray
    null_space_damping: FloatArray
    max_environment_stiffness: float = 1.0e5

    @classmethod
    def from_flat_dict(cls, values: Mapping[str, object] | None = None) -> ControllerParameters:
        """Validate flat dotted names (defaults for the missing ones) into parameters.

        Raises:
            ControlParameterError: for an unknown name, a wrong type, a value out of range, a
                non-positive-definite P, B_d, K, K_pp or K_pv, or a negative gain.
        """
        v = _merged(CONTROLLER_PARAMETER_SPECS, values or {})

        def number(name: str) -> float:
            value = v[name]
            assert isinstance(value, (int, float))
            return float(value)

        def floats(name: str) -> list[float]:
            value = v[name]
            assert isinstance(value, list)
            return [float(x) for x in value]

        def per_coordinate(name: str) -> FloatArray:
            data = np.asarray(floats(name))
            if data.size < 6 + 3:
                raise ControlParameterError(name, data.tolist(), PER_COORDINATE)
            return data

        fuzzy = FuzzySwitchParameters(
            force_small=_membership(
                'fuzzy.force_ratio_small', floats('fuzzy.force_ratio_small'), 'left'
            ),
            force_medium=_membership(
                'fuzzy.force_ratio_medium', floats('fuzzy.force_ratio_medium'), 'inner'
            ),
            force_large=_membership(
                'fuzzy.force_ratio_large', floats('fuzzy.force_ratio_large'), 'right'
            ),
            velocity_slow=_membership(
                'fuzzy.normal_velocity_slow_m_s', floats('fuzzy.normal_velocity_slow_m_s'), 'left'
            ),
            velocity_fast=_membership(
                'fuzzy.normal_velocity_fast_m_s', floats('fuzzy.normal_velocity_fast_m_s'), 'right'
            ),
            weight_small=_membership('fuzzy.weight_small', floats('fuzzy.weight_small'), 'inner'),
            weight_medium=_membership(
                'fuzzy.weight_medium', floats('fuzzy.weight_medium'), 'inner'
            ),
            weight_large=_membership('fuzzy.weight_large', floats('fuzzy.weight_large'), 'inner'),
            no_rule_weight=number('fuzzy.no_rule_weight'),
        )
        mode = v['mode']
        if mode not in SWITCH_MODES:
            raise ControlParameterError('mode', mode, f'one of {list(SWITCH_MODES)}')
        enabled = v['null_space.enabled']
        assert isinstance(enabled, bool)
        threshold = number('force.contact_threshold_n')
        return cls(
            mass_scale=number('model.mass_scale'),
            impedance_inertia=spd_matrix('impedance.inertia_kg', floats('impedance.inertia_kg')),
            impedance_damping=spd_matrix(
                'impedance.damping_n_s_m', floats('impedance.damping_n_s_m')
            ),
            impedance_stiffness=spd_matrix(
                'impedance.stiffness_n_m', floats('impedance.stiffness_n_m')
            ),
            force_direction=_unit3('hybrid.force_direction', floats('hybrid.force_direction')),
            position_kp=spd_matrix('hybrid.position_kp', floats('hybrid.position_kp')),
            position_kd=spd_matrix('hybrid.position_kd', floats('hybrid.position_kd')),
            force_kp=number('hybrid.force_kp'),
            force_ki=number('hybrid.force_ki'),
            force_kd=number('hybrid.force_kd'),
            force_feedforward_compliance=number('hybrid.force_feedforward_compliance_m_n'),
            force_derivative_cutoff_hz=number('hybrid.force_derivative_cutoff_hz'),
            force_integral_limit=number('hybrid.force_integral_limit_n_s'),
            switch_mode=str(mode),
            fuzzy=fuzzy,
            contact_threshold=threshold,
            null_space_enabled=enabled,
            null_space_stiffness=per_coordinate('null_space.stiffness_1_s2'),
            null_space_damping=per_coordinate('null_space.damping_1_s'),
            max_environment_stiffness=number('stability.max_environment_stiffness_n_m'),
        )


def validate_node_parameters(
    specs: Sequence[ParameterSpec], values: Mapping[str, object]
) -> dict[str, object]:
    """Validate node-level parameters (trigger mode, rates, timeouts) against their specs.

    Raises:
        ControlParameterError: for a value out of range or an unknown trigger mode.
    """
    merged = _merged(specs, values)
    mode = merged.get('trigger_mode')
    modes = CONTROLLER_TRIGGER_MODES if 'state_source' in merged else TRIGGER_MODES
    if mode is not None and mode not in modes:
        raise ControlParameterError('trigger_mode', mode, f'one of {list(modes)}')
    source = merged.get('state_source')
    if source is not None and source not in STATE_SOURCES:
        raise ControlParameterError('state_source', source, f'one of {list(STATE_SOURCES)}')
    return merged


def topic_for(topic: str, state_source: str) -> str:
    """The topic the controller reads an input from: odometry/filtered for an estimate.

    >>> topic_for('odometry', 'estimate'), topic_for('odometry', 'truth')
    ('odometry/filtered', 'odometry')
    """
    return 'odometry/filtered' if topic == 'odometry' and state_source == 'estimate' else topic


PER_COORDINATE = '6 + n values: x, y, z, roll, pitch, yaw, then one per arm joint (n >= 3)'
"""What a per-coordinate gain (K_n, D_n of the null space) holds."""


def null_space_gains(params: ControllerParameters, n_dof: int) -> FloatArray:
    """Rows K_n and D_n (2, 6 + n) of the null-space law (eq. 24), checked against the model.

    Raises:
        ControlParameterError: A gain vector whose length is not the model's 6 + n.
    """
    for name, gains in (('null_space.stiffness_1_s2', params.null_space_stiffness),
                        ('null_space.damping_1_s', params.null_space_damping)):
        if gains.size != n_dof:
            raise ControlParameterError(name, gains.tolist(),
                                        f'{n_dof} values for this robot; {PER_COORDINATE}')
    return np.array((params.null_space_stiffness, params.null_space_damping), dtype=float)
