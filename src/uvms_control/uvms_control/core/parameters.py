"""Parameters of the controller and the allocator: specs for ROS declarations, validated values.

Each ``*_PARAMETER_SPECS`` list is the single source of the names, defaults, units and ranges
that the nodes declare (with descriptors) and that ``config/controller.yaml`` sets. The
``from_flat_dict`` constructors validate values and raise `ControlParameterError` naming the
parameter, the value and the valid range.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from uvms_control.core.errors import ControlParameterError
from uvms_control.core.fuzzy_switch import FuzzySwitchParameters, Trapezoid
from uvms_control.core.thruster_dynamics import ThrusterModelParameters

FloatArray = npt.NDArray[np.float64]
ParameterValue = float | int | bool | str | list[float]


class ParameterSpec(NamedTuple):
    """One ROS parameter: name, default, description with unit, range, read-only flag."""

    name: str
    default: ParameterValue
    description: str
    min_value: float | None = None
    max_value: float | None = None
    read_only: bool = True


TRIGGER_MODES = ('lockstep', 'timer')
SWITCH_MODES = ('fuzzy', 'impedance', 'hybrid')

CONTROLLER_NODE_PARAMETER_SPECS: list[ParameterSpec] = [
    ParameterSpec(
        'trigger_mode',
        'lockstep',
        "'lockstep': compute once joint states, odometry and wrench with the same stamp have "
        "arrived and stamp the command alike; 'timer': compute at control_rate_hz on the "
        'latest inputs (real time).',
    ),
    ParameterSpec('control_rate_hz', 500.0, 'Control rate in timer mode (Hz).', 1.0, 10000.0),
    ParameterSpec(
        'watchdog_timeout_s',
        0.2,
        'Inputs older than this (node-clock time) are stale: the controller then publishes '
        'zero generalized force until fresh inputs arrive (s).',
        1e-3,
        60.0,
    ),
]

CONTROLLER_PARAMETER_SPECS: list[ParameterSpec] = [
    ParameterSpec(
        'model.mass_scale',
        1.0,
        "Scale s of the controller's inertia estimate, M_hat = s M_tilde (eq. 34); the "
        "paper's Case IV uses 0.9 (-).",
        0.1,
        10.0,
    ),
    ParameterSpec(
        'impedance.inertia_kg',
        [50.0, 50.0, 50.0],
        'Target inertia P of eq. 21 (kg): 3 diagonal entries or 9 row-major entries of a '
        'symmetric positive-definite matrix.',
    ),
    ParameterSpec(
        'impedance.damping_n_s_m',
        [1000.0, 1000.0, 1000.0],
        'Target damping B_d of eq. 21 (N s/m): 3 diagonal or 9 row-major entries, SPD.',
    ),
    ParameterSpec(
        'impedance.stiffness_n_m',
        [3000.0, 3000.0, 3000.0],
        'Target stiffness K of eq. 21 (N/m): 3 diagonal or 9 row-major entries, SPD.',
    ),
    ParameterSpec(
        'hybrid.force_direction',
        [1.0, 0.0, 0.0],
        'Direction n along which force is controlled, the environment normal pointing into '
        'the environment, in map_ned (-); selection matrix S = n n^T (eq. 35).',
    ),
    ParameterSpec(
        'hybrid.position_kp',
        [100.0, 100.0, 100.0],
        'Position gain K_pp of eq. 37 (1/s^2): 3 diagonal or 9 row-major entries, SPD.',
    ),
    ParameterSpec(
        'hybrid.position_kd',
        [20.0, 20.0, 20.0],
        'Velocity gain K_pv of eq. 37 (1/s): 3 diagonal or 9 row-major entries, SPD.',
    ),
    ParameterSpec(
        'hybrid.force_kp',
        0.05,
        'Force gain K_fp of eq. 39 along n ((m/s^2)/N).',
        0.0,
        1e3,
    ),
    ParameterSpec(
        'hybrid.force_ki',
        0.2,
        'Force integral gain K_fi of eq. 39 along n ((m/s^2)/(N s)).',
        0.0,
        1e3,
    ),
    ParameterSpec(
        'hybrid.force_kd',
        0.003,
        'Force derivative gain K_fv of eq. 39 along n ((m/s^2)/(N/s)).',
        0.0,
        1e3,
    ),
    ParameterSpec(
        'hybrid.force_feedforward_compliance_m_n',
        0.0,
        'Compliance c multiplying F_d_ddot in eq. 39, which the paper adds to an acceleration '
        'without a unit; c = 1/K_e would need the environment stiffness that the method does '
        'without, so 0 by default (m/N).',
        0.0,
        1.0,
    ),
    ParameterSpec(
        'hybrid.force_derivative_cutoff_hz',
        20.0,
        'Cut-off of the filtered force derivative in eq. 39 (Hz).',
        0.1,
        1e4,
    ),
    ParameterSpec(
        'hybrid.force_integral_limit_n_s',
        50.0,
        'Clamp on the force-error integral of eq. 39 (N s): anti-windup.',
        0.0,
        1e6,
    ),
    ParameterSpec(
        'mode',
        'fuzzy',
        "How W of eq. 2 is set: 'fuzzy' (sec. 4.3), or fixed for comparisons: 'impedance' "
        "(W = 1) or 'hybrid' (W = 0).",
    ),
    ParameterSpec(
        'fuzzy.force_ratio_small',
        [0.1, 0.5],
        'FS on F_e/F_d (-), left shoulder: 1 up to the first value, 0 from the second.',
    ),
    ParameterSpec(
        'fuzzy.force_ratio_medium',
        [0.1, 0.5, 0.9],
        'FM on F_e/F_d (-): triangle [left, peak, right] or trapezoid [a, b, c, d].',
    ),
    ParameterSpec(
        'fuzzy.force_ratio_large',
        [0.5, 0.9],
        'FL on F_e/F_d (-), right shoulder: 0 up to the first value, 1 from the second.',
    ),
    ParameterSpec(
        'fuzzy.normal_velocity_slow_m_s',
        [0.05, 0.15],
        'VS on v_e (m/s, positive toward the environment), left shoulder: 1 up to the first '
        'value, 0 from the second.',
    ),
    ParameterSpec(
        'fuzzy.normal_velocity_fast_m_s',
        [0.05, 0.15],
        'VF on v_e (m/s), right shoulder: 0 up to the first value, 1 from the second.',
    ),
    ParameterSpec(
        'fuzzy.weight_small',
        [-0.5, 0.0, 0.5],
        'WS on W (-): triangle [left, peak, right] or trapezoid [a, b, c, d].',
    ),
    ParameterSpec(
        'fuzzy.weight_medium',
        [0.0, 0.5, 1.0],
        'WM on W (-): triangle or trapezoid.',
    ),
    ParameterSpec(
        'fuzzy.weight_large',
        [0.5, 1.0, 1.5],
        'WL on W (-): triangle or trapezoid.',
    ),
    ParameterSpec(
        'fuzzy.no_rule_weight',
        1.0,
        'W where no rule fires (-); 1 = impedance control, safe for free motion and impact.',
        0.0,
        1.0,
    ),
    ParameterSpec(
        'reference.radius_m', 0.1, 'Radius of the half circle (m); paper sec. 5.1.', 1e-4, 10.0
    ),
    ParameterSpec('reference.duration_s', 16.0, 'Time to run the half circle (s).', 1e-3, 1e5),
    ParameterSpec(
        'reference.start_delay_s',
        2.0,
        'Time at the start point before the half circle begins (s), counted from the first '
        'controller step.',
        0.0,
        1e5,
    ),
    ParameterSpec(
        'reference.sweep_direction',
        [0.0, 0.0, 1.0],
        'Direction of the half circle diameter in map_ned (-); default down (+z).',
    ),
    ParameterSpec(
        'reference.capture_start',
        True,
        'Start the half circle at the end-effector position of the first state (true) or at '
        'reference.start_position_m (false).',
    ),
    ParameterSpec(
        'reference.start_position_m',
        [0.0, 0.0, 0.0],
        'Start of the half circle in map_ned when reference.capture_start is false (m).',
    ),
    ParameterSpec(
        'force.setpoint_n', 150.0, 'Desired contact force along n (N); paper sec. 5.2.', 1e-3, 1e5
    ),
    ParameterSpec(
        'force.ramp_time_s',
        1.0,
        'Duration of the quintic ramp of the force set-point after contact, and of its '
        'release (s).',
        1e-3,
        1e4,
    ),
    ParameterSpec(
        'force.contact_threshold_n',
        5.0,
        'Normal force that counts as contact and starts the force ramp (N); well above the '
        'sensor noise (0.1 % of range).',
        1e-3,
        1e5,
    ),
    ParameterSpec(
        'null_space.enabled',
        True,
        'Add the null-space term of eq. 24 that holds vehicle pose and arm posture (true), or '
        'apply tau = J^T F_c alone as the paper does (false).',
    ),
    ParameterSpec(
        'null_space.stiffness_1_s2',
        [4.0] * 6 + [2.0] * 3,
        'Posture stiffness K_n (1/s^2) per coordinate x, y, z, roll, pitch, yaw, q1..q3: '
        'phi_ddot = K_n (q_0 - q) - D_n q_dot, projected into the null space of J.',
        0.0,
        1e4,
        True,
    ),
    ParameterSpec(
        'null_space.damping_1_s',
        [4.0] * 6 + [3.0] * 3,
        'Posture damping D_n (1/s) per coordinate, as null_space.stiffness_1_s2.',
        0.0,
        1e4,
    ),
]

ALLOCATOR_PARAMETER_SPECS: list[ParameterSpec] = [
    ParameterSpec(
        'trigger_mode',
        'lockstep',
        "'lockstep': answer each command with the same stamp, integrating the thrusters over "
        "the time between command stamps; 'timer': step at rate_hz on the latest command.",
    ),
    ParameterSpec('rate_hz', 500.0, 'Allocator rate in timer mode (Hz).', 1.0, 10000.0),
    ParameterSpec(
        'watchdog_timeout_s',
        0.2,
        'A command older than this (node-clock time) is stale: thrusters and motors are '
        'commanded to zero (s).',
        1e-3,
        60.0,
    ),
    ParameterSpec(
        'max_step_s',
        0.1,
        'Longest interval between command stamps that the thruster dynamics integrate over in '
        'lockstep; a longer gap (a restart, a paused clock) restarts the integration (s).',
        1e-4,
        10.0,
    ),
    ParameterSpec(
        'allocator.max_joint_torque_n_m',
        [200.0, 200.0, 200.0],
        'Torque limit of each arm motor (N m); the joint torque vector is scaled as a whole.',
        1e-6,
        1e6,
    ),
    ParameterSpec(
        'thruster.propeller_diameter_m',
        0.15,
        'Propeller diameter D (m); duct area pi D^2 / 4. Sized so that the 200 N thrust '
        'limit is reached near 1750 rpm.',
        1e-3,
        10.0,
    ),
    ParameterSpec(
        'thruster.thrust_coefficient',
        0.4566,
        'Bollard K_T of T = K_T rho D^4 n^2 (-); 3-blade Wageningen B-series at J = 0.',
        1e-3,
        10.0,
    ),
    ParameterSpec(
        'thruster.reverse_thrust_ratio',
        0.6,
        'Reverse over forward bollard thrust at equal propeller speed (-); the propeller turns '
        'faster in reverse for the same thrust.',
        0.01,
        1.0,
    ),
    ParameterSpec(
        'thruster.pitch_angle_rad',
        math.atan(1.0 / (0.7 * math.pi)),
        'Blade pitch angle p at 0.7 R (rad); default pitch ratio P/D = 1.',
        1e-3,
        1.5,
    ),
    ParameterSpec(
        'thruster.lift_coefficient_max',
        1.2,
        'C_Lmax of C_L = C_Lmax sin 2 alpha (-) (Healey et al. 1995 form).',
        1e-3,
        10.0,
    ),
    ParameterSpec(
        'thruster.drag_coefficient_max',
        1.0,
        'C_Dmax of C_D = C_Dmax (1 - cos 2 alpha) (-); 2 C_Dmax ~ 2 is a flat plate broadside.',
        0.0,
        10.0,
    ),
    ParameterSpec('thruster.duct_length_m', 0.1, 'Duct length L_d (m).', 1e-4, 10.0),
    ParameterSpec(
        'thruster.duct_added_mass_ratio',
        1.0,
        'gamma: effective fluid mass in the duct over rho A_p L_d (-).',
        1e-3,
        100.0,
    ),
    ParameterSpec(
        'thruster.momentum_flux_coefficient',
        1.0,
        'Delta beta of the duct momentum balance (-).',
        1e-3,
        100.0,
    ),
    ParameterSpec(
        'thruster.motor_inertia_kg_m2',
        2.0e-3,
        'J_m: motor, propeller and entrained water (kg m^2).',
        1e-7,
        10.0,
    ),
    ParameterSpec(
        'thruster.motor_torque_constant_n_m_a',
        0.2,
        'Motor torque constant K_t (N m/A).',
        1e-5,
        100.0,
    ),
    ParameterSpec(
        'thruster.motor_viscous_friction_n_m_s',
        1.0e-3,
        'Motor viscous friction K_f (N m s/rad).',
        0.0,
        100.0,
    ),
    ParameterSpec(
        'thruster.speed_feedback_gain_a_s',
        0.2,
        'Speed feedback gain K_fb of the motor driver (A s/rad).',
        0.0,
        1e3,
    ),
    ParameterSpec(
        'thruster.max_motor_current_a',
        40.0,
        'Motor current limit i_max (A); must hold the largest thrust limit.',
        1e-3,
        1e4,
    ),
]


def _spec_defaults(specs: Sequence[ParameterSpec]) -> dict[str, ParameterValue]:
    return {spec.name: spec.default for spec in specs}


def _merged(specs: Sequence[ParameterSpec], values: Mapping[str, object]) -> dict[str, object]:
    """Defaults overridden by ``values``; unknown names and out-of-range numbers raise."""
    known = {spec.name: spec for spec in specs}
    merged: dict[str, object] = dict(_spec_defaults(specs))
    for name, value in values.items():
        if name not in known:
            raise ControlParameterError(
                name, value, f'one of the known parameters {sorted(known)}'
            )
        merged[name] = value
    for name, spec in known.items():
        value = merged[name]
        kind = type(spec.default)
        if kind is bool:
            if not isinstance(value, bool):
                raise ControlParameterError(name, value, 'a bool')
        elif kind is str:
            if not isinstance(value, str):
                raise ControlParameterError(name, value, 'a string')
        elif kind is float:
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ControlParameterError(name, value, 'a number')
        elif kind is list:
            if isinstance(value, (str, bytes)) or not hasattr(value, '__iter__'):
                raise ControlParameterError(name, value, 'a list of numbers')
            items = list(value)
            if not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in items):
                raise ControlParameterError(name, value, 'a list of numbers')
            merged[name] = [float(v) for v in items]
        numbers: list[float] = []
        current = merged[name]
        if isinstance(current, list):
            numbers = [float(v) for v in current]
        elif isinstance(current, (int, float)) and not isinstance(current, bool):
            numbers = [float(current)]
        for number in numbers:
            if not math.isfinite(number):
                raise ControlParameterError(name, current, 'finite values')
            lo, hi = spec.min_value, spec.max_value
            if (lo is not None and number < lo) or (hi is not None and number > hi):
                raise ControlParameterError(
                    name,
                    current,
                    f'values in [{"-inf" if lo is None else lo}, {"inf" if hi is None else hi}]',
                )
    return merged


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
    reference_radius: float
    reference_duration: float
    reference_start_delay: float
    reference_sweep_direction: FloatArray
    reference_start_position: FloatArray | None
    force_setpoint: float
    force_ramp_time: float
    contact_threshold: float
    null_space_enabled: bool
    null_space_stiffness: FloatArray
    null_space_damping: FloatArray

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

        def nine(name: str) -> FloatArray:
            data = np.asarray(floats(name))
            if data.size != 9:
                raise ControlParameterError(name, data.tolist(), '9 values (one per coordinate)')
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
        capture = v['reference.capture_start']
        assert isinstance(capture, bool)
        enabled = v['null_space.enabled']
        assert isinstance(enabled, bool)
        setpoint = number('force.setpoint_n')
        threshold = number('force.contact_threshold_n')
        if threshold >= setpoint:
            raise ControlParameterError(
                'force.contact_threshold_n', threshold, f'(0, force.setpoint_n = {setpoint}) N'
            )
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
            reference_radius=number('reference.radius_m'),
            reference_duration=number('reference.duration_s'),
            reference_start_delay=number('reference.start_delay_s'),
            reference_sweep_direction=_unit3(
                'reference.sweep_direction', floats('reference.sweep_direction')
            ),
            reference_start_position=None
            if capture
            else _vector3('reference.start_position_m', floats('reference.start_position_m')),
            force_setpoint=setpoint,
            force_ramp_time=number('force.ramp_time_s'),
            contact_threshold=threshold,
            null_space_enabled=enabled,
            null_space_stiffness=nine('null_space.stiffness_1_s2'),
            null_space_damping=nine('null_space.damping_1_s'),
        )


def thruster_parameters_from_flat_dict(
    values: Mapping[str, object], water_density: float = 1025.0
) -> ThrusterModelParameters:
    """Thruster model constants from the ``thruster.*`` names of ALLOCATOR_PARAMETER_SPECS.

    Args:
        values: flat dotted names to values; missing names keep their defaults.
        water_density: ρ (kg/m³), the robot's ``hydrodynamics.water_density_kg_m3``.

    Raises:
        ControlParameterError: for an unknown name or a value out of range.
    """
    specs = [s for s in ALLOCATOR_PARAMETER_SPECS if s.name.startswith('thruster.')]
    v = _merged(specs, values)

    def number(name: str) -> float:
        value = v[name]
        assert isinstance(value, (int, float))
        return float(value)

    return ThrusterModelParameters(
        water_density=water_density,
        propeller_diameter=number('thruster.propeller_diameter_m'),
        thrust_coefficient=number('thruster.thrust_coefficient'),
        reverse_thrust_ratio=number('thruster.reverse_thrust_ratio'),
        pitch_angle=number('thruster.pitch_angle_rad'),
        lift_coefficient_max=number('thruster.lift_coefficient_max'),
        drag_coefficient_max=number('thruster.drag_coefficient_max'),
        duct_length=number('thruster.duct_length_m'),
        duct_added_mass_ratio=number('thruster.duct_added_mass_ratio'),
        momentum_flux_coefficient=number('thruster.momentum_flux_coefficient'),
        motor_inertia=number('thruster.motor_inertia_kg_m2'),
        motor_torque_constant=number('thruster.motor_torque_constant_n_m_a'),
        motor_viscous_friction=number('thruster.motor_viscous_friction_n_m_s'),
        speed_feedback_gain=number('thruster.speed_feedback_gain_a_s'),
        max_motor_current=number('thruster.max_motor_current_a'),
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
    if mode is not None and mode not in TRIGGER_MODES:
        raise ControlParameterError('trigger_mode', mode, f'one of {list(TRIGGER_MODES)}')
    return merged
