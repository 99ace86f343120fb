"""Validated parameters of the thruster allocator, checked against their specs.

``ALLOCATOR_PARAMETER_SPECS`` (``uvms_thrusters.parameter_specs``) is the single source of
the names, defaults, units and ranges that the allocator node declares; these validate
values and raise `ThrusterParameterError` naming the parameter, the value and the valid range.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from uvms_common.parameter_spec import TRIGGER_MODES, ParameterSpec, merged_values

from uvms_thrusters.errors import ThrusterParameterError
from uvms_thrusters.parameter_specs import ALLOCATOR_PARAMETER_SPECS
from uvms_thrusters.thruster_dynamics import ThrusterModelParameters

#: What the allocator's command/actuators carries (parameter ``thruster_output``).
THRUSTER_OUTPUTS = ('actual', 'desired')


def thruster_parameters_from_flat_dict(
    values: Mapping[str, object], water_density: float = 1025.0
) -> ThrusterModelParameters:
    """Thruster model constants from the ``thruster.*`` names of ALLOCATOR_PARAMETER_SPECS.

    Args:
        values: flat dotted names to values; missing names keep their defaults.
        water_density: ρ (kg/m³), the robot's ``hydrodynamics.water_density_kg_m3``.

    Raises:
        ThrusterParameterError: for an unknown name or a value out of range.
    """
    specs = [s for s in ALLOCATOR_PARAMETER_SPECS if s.name.startswith('thruster.')]
    v = merged_values(specs, values, ThrusterParameterError)

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
    """Validate the allocator's node-level parameters (trigger mode, timeouts) against specs.

    Raises:
        ThrusterParameterError: for a value out of range or an unknown trigger mode.
    """
    merged = merged_values(specs, values, ThrusterParameterError)
    output = merged.get('thruster_output')
    if output is not None and output not in THRUSTER_OUTPUTS:
        raise ThrusterParameterError('thruster_output', output,
                                     f'one of {list(THRUSTER_OUTPUTS)}')
    mode = merged.get('trigger_mode')
    if mode is not None and mode not in TRIGGER_MODES:
        raise ThrusterParameterError('trigger_mode', mode, f'one of {list(TRIGGER_MODES)}')
    return merged
