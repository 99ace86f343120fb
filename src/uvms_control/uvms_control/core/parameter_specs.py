"""ROS parameter specs of the controller: names, defaults, units, ranges.

The thruster allocator's are in ``uvms_thrusters.parameter_specs``; `ParameterSpec` and the
allocator's TRIGGER_MODES in ``uvms_common.parameter_spec``.
"""

from __future__ import annotations

from uvms_common.parameter_spec import TRIGGER_MODES, ParameterSpec

#: The controller's trigger modes: the allocator's and 'odometry' (a step per vehicle state).
CONTROLLER_TRIGGER_MODES = (*TRIGGER_MODES, 'odometry')
STATE_SOURCES = ('truth', 'estimate')
SWITCH_MODES = ('fuzzy', 'impedance', 'hybrid')

CONTROLLER_NODE_PARAMETER_SPECS: list[ParameterSpec] = [
    ParameterSpec(
        'trigger_mode',
        'lockstep',
        "'lockstep': compute once joint states, odometry and wrench with the same stamp have "
        "arrived and stamp the command alike; 'timer': compute at control_rate_hz on the "
        "latest inputs (real time); 'odometry': compute on each vehicle state (odometry, or "
        'odometry/filtered on the estimate) with the latest joint states and wrench, stamped '
        'with its stamp (real time on the estimate).',
    ),
    ParameterSpec('control_rate_hz', 500.0, 'Control rate in timer mode (Hz).', 1.0, 10000.0),
    ParameterSpec(
        'state_source', 'truth',
        "Where the vehicle state comes from: 'truth' reads odometry (the simulator's ground "
        "truth, the paper's assumption); 'estimate' reads odometry/filtered (the estimator of "
        'uvms_navigation on the navigation sensors). Joint states stay the encoders.',
    ),
    ParameterSpec(
        'state_rate_hz', 0.0,
        'Rate of controller/state (Hz): the first step of each 1/rate window; 0 publishes it '
        'with every step. No node of the loop needs it; a lower rate saves a lockstep run time '
        '(the recording and the metrics then see fewer samples).',
        0.0, 10000.0,
    ),
    ParameterSpec(
        'watchdog_timeout_s',
        0.2,
        'Inputs older than this (node-clock time) are stale: the controller then publishes '
        'zero generalized force until fresh inputs arrive (s).',
        1e-3,
        60.0,
    ),
    ParameterSpec(
        'allocator_node',
        'thruster_allocator',
        "Name of the thruster allocator node (in the controller's namespace) whose "
        "'<name>/transition_event' tells the controller when it is not active: the controller "
        "then ends a running task INPUTS_STALE and commands zero. '' watches no allocator.",
    ),
    ParameterSpec(
        'arm.command_rate_hz', 0.0,
        'Rate at which the arm applies joint commands, each held until the next (Hz; the '
        "Alpha 5's bus: 77 Hz, robots/bluerov2_alpha5/device_timing.yaml). Above 0 the "
        'control law cancels the contact force predicted for the middle of a held slot '
        '(core/law/held_command.py, eq. 29 and 35); 0: every command at once (ideal devices, '
        'the paper).',
        0.0, 10000.0,
    ),
    ParameterSpec(
        'arm.hold_in_joint_space', False,
        "While no task runs, hold the arm's joints where they are (computed torque on the "
        "model's arm, core/task/joint_hold.py) and command the vehicle nothing, instead of "
        'holding the end effector in map_ned: for experiments whose thrusts are planned '
        '(uvms identify plan), where the arm reaching for a world-fixed point tilts the '
        "vehicle. A pilot's twists move nothing while it holds. Off: the paper's hold.",
    ),
    ParameterSpec('arm.joint_hold_frequency_hz', 2.0,
                  "Natural frequency of the joint hold on every joint (Hz): computed torque on "
                  "the arm's mass matrix", 0.01, 50.0),
    ParameterSpec('arm.joint_hold_damping_ratio', 1.0,
                  'Damping ratio of the joint hold (1: critically damped)', 0.01, 10.0),
    ParameterSpec(
        'arm.force_latency_s', 0.0,
        "Age of the wrist force beyond its stamp (s): the sensor's latency as the controller "
        'sees it (the simulator with device timing: one state, 0.002 s; a sensor stamping its '
        "samples with its own clock: its event-to-output latency). The samples' age at the "
        'step is added as measured. Used only when arm.command_rate_hz is above 0.',
        0.0, 1.0,
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
        'force.contact_threshold_n',
        5.0,
        'Normal force that counts as contact and starts the force ramp (N); well above the '
        'sensor noise (0.1 % of range).',
        1e-3,
        1e5,
        False,
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
        'Posture stiffness K_n (1/s^2) per coordinate x, y, z, roll, pitch, yaw, then one per '
        'arm joint (6 + n values; the default fits the paper robot): '
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
    ParameterSpec(
        'stability.max_environment_stiffness_n_m',
        1.0e5,
        'Stiffest surface K_e (N/m) the gains must hold: configure and set_parameters refuse '
        'gains whose sampled impedance, hybrid or blended loop on a wall this stiff, or in free '
        "motion, is unstable at control_rate_hz (the paper's stiffest wall, Case I: 1e5).",
        1.0,
        1e9,
    ),
]

#: Controller parameters that ``set_parameters`` may change while the node runs: the gains of
#: the laws and the switch, the contact threshold and the null-space gains. The model, the
#: switch mode, the default normal, rates and topology stay read-only.
RUNTIME_PREFIXES = ('impedance.', 'hybrid.position_', 'hybrid.force_k',
                    'hybrid.force_feedforward', 'hybrid.force_derivative',
                    'hybrid.force_integral', 'fuzzy.', 'force.', 'null_space.stiffness',
                    'null_space.damping', 'safety.', 'stability.')

CONTROLLER_PARAMETER_SPECS = [
    spec._replace(read_only=not spec.name.startswith(RUNTIME_PREFIXES))
    for spec in CONTROLLER_PARAMETER_SPECS
]

#: Safety limits of the contact tasks (``contact_task.SafetyLimits``), changeable at run time.
SAFETY_PARAMETER_SPECS: list[ParameterSpec] = [
    ParameterSpec(
        'safety.max_contact_force_n', 400.0,
        'Largest measured contact force along the task normal (N): beyond it the task ends '
        'FORCE_LIMIT and the arm backs off; a goal asking more is refused.', 1.0, 1e5, False,
    ),
    ParameterSpec(
        'safety.sensor_range_n', 400.0,
        'Full scale of the wrist force/torque sensor per axis (N): a reading at 99.9 % of it '
        'counts as saturated (FORCE_LIMIT).', 1.0, 1e6, False,
    ),
    ParameterSpec(
        'safety.max_position_error_m', 0.2,
        'Largest end-effector tracking error |X_d - X| (m): beyond it the task ends '
        'TRACKING_LIMIT.', 1e-3, 100.0, False,
    ),
    ParameterSpec(
        'safety.max_path_distance_m', 1.5,
        "Largest distance of a goal's waypoint from the end effector at acceptance (m).",
        1e-3, 1000.0, False,
    ),
    ParameterSpec(
        'safety.retreat_m', 0.05,
        'Back-off along -normal after a cancel or a limit (m).', 0.0, 10.0, False,
    ),
    ParameterSpec(
        'safety.retreat_time_s', 1.0,
        'Time of the back-off and of the force ramp-down with it (s).', 1e-3, 100.0, False,
    ),
    ParameterSpec(
        'safety.max_target_speed_m_s', 0.1,
        'Speed limit of the streamed hold target (target_position topic) (m/s).', 1e-4, 10.0,
        False,
    ),
    ParameterSpec(
        'safety.max_goal_delay_s', 60.0,
        "How far ahead of the controller clock a goal's header.stamp may be (s); a later "
        'stamp is refused (INVALID_GOAL).', 0.0, 1e6, False,
    ),
    ParameterSpec(
        'safety.max_path_speed_m_s', 0.5,
        "Largest speed |X_d dot| of a goal's interpolated path, user velocities included "
        '(m/s); also bounds the back-off, 1.875 retreat_m / retreat_time_s.', 1e-3, 100.0,
        False,
    ),
    ParameterSpec(
        'safety.max_path_acceleration_m_s2', 1.0,
        "Largest acceleration |X_d ddot| of a goal's interpolated path (m/s^2).", 1e-3, 1000.0,
        False,
    ),
    ParameterSpec(
        'safety.min_ramp_s', 0.1,
        "Shortest force ramp (a goal's force_ramp_s) and safety.retreat_time_s (s): 50 "
        'control periods at 500 Hz.', 1e-3, 100.0, False,
    ),
]
