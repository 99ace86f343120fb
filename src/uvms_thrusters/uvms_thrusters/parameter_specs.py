"""ROS parameter specs of the thruster allocator: names, defaults, units, ranges."""

from __future__ import annotations

import math

from uvms_common.parameter_spec import ParameterSpec

ALLOCATOR_PARAMETER_SPECS: list[ParameterSpec] = [
    ParameterSpec(
        'trigger_mode',
        'lockstep',
        "'lockstep': answer each command with the same stamp, integrating the thrusters over "
        "the time between command stamps; 'timer': step at rate_hz on the latest command.",
    ),
    ParameterSpec(
        'thruster_output',
        'actual',
        "What command/actuators carries: 'actual' thrusts after the thruster dynamics "
        "(eq. 11-15; the simulator's input), or 'desired' thrusts as allocated (eq. 10), for "
        'a vehicle whose propellers do the dynamics (uvms launch --hardware: the bridges '
        'turn them into PWM).',
    ),
    ParameterSpec('rate_hz', 500.0, 'Allocator rate in timer mode (Hz).', 1.0, 10000.0),
    ParameterSpec(
        'state_rate_hz', 0.0,
        'Rate of thrusters/state (Hz): the first step of each 1/rate window; 0 publishes it '
        'with every step. No node of the loop needs it.',
        0.0, 10000.0,
    ),
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
