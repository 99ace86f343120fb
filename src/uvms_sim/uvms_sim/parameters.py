"""Simulator parameters: names, defaults, units, valid ranges, and their validation.

The robot's own parameters (model, wall contact, wrist sensor, integrator) are
``uvms_model.PARAMETER_SPECS``, shared with the controller through ``config/robot.yaml``;
these are the simulator's. Pure Python: the node turns each ``ParameterSpec`` into a ROS
parameter with a descriptor, reads the values back, and hands them to
``SimulatorSettings.from_values``, which checks every value against its range before
anything is built.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from uvms_sim.device_timing import SENSORS, DeviceTiming
from uvms_sim.errors import SimParameterError
from uvms_sim.startup import StartupSettings

Value = bool | int | float | str | list[float] | list[str]

MODES = ('lockstep', 'realtime')
INITIAL_ARM_SOURCES = ('joint_positions', 'ee_position')


@dataclass(frozen=True)
class ParameterSpec:
    """One simulator parameter.

    Attributes:
        name: Dotted ROS parameter name.
        default: Default value; its Python type is the parameter type.
        description: What it is, with its unit.
        min_value: Smallest valid value (numbers and number arrays), inclusive.
        max_value: Largest valid value, inclusive.
        choices: Valid values of a string parameter.
        length: Required length of an array parameter.
    """

    name: str
    default: Value
    description: str
    min_value: float | None = None
    max_value: float | None = None
    choices: tuple[str, ...] = ()
    length: int | None = None

    def range_text(self) -> str:
        """The valid range as a user reads it."""
        if self.choices:
            return 'one of ' + ', '.join(repr(c) for c in self.choices)
        if self.min_value is not None and self.max_value is not None:
            text = f'[{self.min_value:g}, {self.max_value:g}]'
            return f'{self.length} values in {text}' if self.length else text
        return 'any value'


SIMULATOR_PARAMETERS: tuple[ParameterSpec, ...] = (
    ParameterSpec(
        'mode', 'lockstep',
        "Execution mode: 'lockstep' steps only when the actuator command for the published "
        "state arrived (deterministic); 'realtime' steps on a wall-clock timer.",
        choices=MODES,
    ),
    ParameterSpec(
        'real_time_factor', 1.0,
        "Real time: simulated seconds per wall-clock second (as Gazebo's real_time_factor); "
        'below 1 a machine too small for the whole graph runs it slower, every node on '
        "/clock; devices on their own clocks (the hardware bridges' rates) are not scaled.",
        0.01, 10.0,
    ),
    ParameterSpec(
        'physics_rate_hz', 1000.0,
        'Integration rate of the plant (Hz); the fixed step is its inverse.',
        1.0, 100000.0,
    ),
    ParameterSpec(
        'publish_rate_hz', 500.0,
        'Rate of the sensor topics and /clock, the control rate (Hz); must divide '
        'physics_rate_hz.',
        1.0, 100000.0,
    ),
    ParameterSpec(
        'tf_rate_hz', 50.0,
        'Rate of /tf (Hz), rounded to a whole number of sensor publications; 0 disables '
        '/tf and /tf_static.',
        0.0, 100000.0,
    ),
    ParameterSpec(
        'ground_truth_rate_hz', 500.0,
        'Rate of ee_pose and contact (Hz), rounded to a whole number of sensor publications '
        '(at or above publish_rate_hz: with every state); no node of the control loop needs '
        'them, so a lower rate saves a lockstep run time (the recording holds fewer).',
        1.0, 100000.0,
    ),
    ParameterSpec(
        'joint_states_rate_hz', 0.0,
        'Real time: rate of joint_states (Hz), rounded to a whole number of sensor '
        'publications, as an arm bus delivers its encoders (the Alpha 5 bridge: 125 Hz); 0: '
        'with every state. Below the state rate only for a controller that steps on the '
        "estimate (trigger_mode 'odometry'): one on complete states waits for joint_states.",
        0.0, 100000.0,
    ),
    ParameterSpec(
        'lockstep_timeout_s', 1.0,
        'Lockstep: wall-clock time to wait for the actuator command of the published state '
        "before stepping with the last command anyway, counted while the simulator's process "
        'runs its timer on time (a loaded machine delays, it does not time out) (s).',
        0.001, 3600.0,
    ),
    ParameterSpec(
        'startup.hold', True,
        'Real time: hold the initial state (simulated time stands still) until the control '
        'loop is closed (startup.nodes active, a generalized force and then an actuator '
        'command arrived); false steps from the first tick (a simulator driven by hand).',
    ),
    ParameterSpec(
        'startup.timeout_s', 60.0,
        'Wall time for the control loop to close after the initial state is first published '
        '(lockstep: its actuator command; real time: see startup.hold); then the simulator '
        'stops with an error naming the node that did not answer (s); 0 waits forever.',
        0.0, 86400.0,
    ),
    ParameterSpec(
        'startup.nodes', ['controller', 'thruster_allocator'],
        'Real time: managed nodes (names relative to the namespace) that must report the '
        'lifecycle state active (<node>/get_state) before physics starts.',
    ),
    ParameterSpec(
        'startup.recorder', '',
        'A node (name relative to the namespace, e.g. recorder) whose subscriptions to the '
        'state topics (/clock, joint_states, odometry, wrench, ee_pose, contact) must be '
        'matched before the first state is published, so that its recording starts at t = 0 '
        '(both modes; uvms launch sets it when it records); empty: publish at once.',
    ),
    ParameterSpec(
        'startup.recorder_topics', ['*'],
        'With startup.recorder: the topics it records (names as the recorder resolves them, '
        'relative to the namespace or absolute); only the state topics among them are waited '
        "for. ['*'] (the default): every state topic. uvms launch sets it from a scenario's "
        '`recorder: {topics: [...]}`, so that a recorder told to record fewer topics does not '
        'hold the first state until startup.timeout_s.',
    ),
    ParameterSpec(
        'startup.mission', '',
        "A mission's latched readiness topic (relative to the namespace, e.g. mission/ready) "
        'on which True must arrive before physics starts (lockstep: before the first state; '
        'real time with startup.hold: the held state goes out, the hold waits for it too), '
        "so that no goal can start late because the mission was still discovering the "
        "controller's action server (uvms launch and uvms run set it when the scenario has "
        'a mission); empty: none.',
    ),
    ParameterSpec(
        'watchdog_timeout_s', 0.1,
        'Age in simulated time above which an actuator command is stale and thrusters and '
        'motors are set to zero (s).',
        0.0001, 3600.0,
    ),
    ParameterSpec(
        'duration_s', 0.0,
        'Simulated time after which the simulator stops stepping (s); 0 runs forever.',
        0.0, 1.0e7,
    ),
    ParameterSpec(
        'wall_enabled', True,
        'Whether the wall of the contact.* parameters exists (false: free motion).',
    ),
    ParameterSpec(
        'wall_motion_start_force_n', 0.0,
        'Contact force (N) at which a moving wall (contact.wall_speed_m_s) starts to move; '
        '0 starts it at the first touch.',
        0.0, 1.0e6,
    ),
    ParameterSpec(
        'initial.vehicle_pose', [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        'Initial vehicle pose in map_ned: x, y, z (m), roll, pitch, yaw (rad); default: the '
        "robot's start.yaml.",
        -1000.0, 1000.0, length=6,
    ),
    ParameterSpec(
        'initial.arm', 'ee_position',
        "Initial arm configuration from 'joint_positions' or by inverse kinematics from "
        "'ee_position'.",
        choices=INITIAL_ARM_SOURCES,
    ),
    ParameterSpec(
        'initial.joint_positions', [0.0, 0.4, -0.8],
        'Initial arm joint angles (rad), one per arm joint, when initial.arm is '
        'joint_positions; otherwise the starting guess of the inverse kinematics (it picks '
        "the elbow branch). The default is the paper arm's elbow-up guess; left at it, an arm "
        'of another joint count starts from zeros.',
        -2.0 * math.pi, 2.0 * math.pi,
    ),
    ParameterSpec(
        'initial.ee_position', [1.7, 0.0, -0.1],
        'Initial end-effector position in map_ned (m), used when initial.arm is ee_position; '
        "default: the robot's start.yaml.",
        -1000.0, 1000.0, length=3,
    ),
)

_SIGNAL_TEXT = {
    'joint_states': "the arm joints' positions, velocities and efforts (joint_states)",
    'wrench': 'the wrist sensor (wrench)',
    'imu': 'the IMU (imu; its rate is navigation.imu.rate_hz)',
    'dvl': "the DVL (dvl; its rate is navigation.dvl's, by altitude)",
    'depth': 'the depth sensor (depth; its rate is navigation.depth.rate_hz)',
}


def _device_specs() -> tuple[ParameterSpec, ...]:
    """``devices.*``: the robot's device timing (its device_timing.yaml), all ideal by default."""
    specs = [ParameterSpec(
        'devices.ideal', False,
        "Ideal devices: every sensor with every state and undelayed, every command applied "
        "at once (the paper's claims), whatever the robot's device_timing.yaml declares; "
        'false keeps its device timing (docs/robots.md, "Device timing").',
    )]
    for name in SENSORS:
        if name in ('joint_states', 'wrench'):
            specs.append(ParameterSpec(
                f'devices.{name}.rate_hz', 0.0,
                f'Rate at which {_SIGNAL_TEXT[name]} is sampled (Hz), held between samples; '
                '0: with every state.', 0.0, 100000.0))
        if name == 'joint_states':
            specs.append(ParameterSpec(
                'devices.joint_states.staggered', False,
                'The arm joints sampled one at a time, evenly over each 1/rate_hz round, the '
                'round delivered whole after its last joint (a polled bus answers one device '
                'at a time); false: every joint at each sample.'))
        specs.append(ParameterSpec(
            f'devices.{name}.latency_s', 0.0,
            f'Latency of {_SIGNAL_TEXT[name]} from the sample to its delivery (s), delivered '
            'with the first state at or after it; 0: none.', 0.0, 10.0))
        specs.append(ParameterSpec(
            f'devices.{name}.jitter_s', 0.0,
            f'Half width of the uniform spread of devices.{name}.latency_s (s), at most it.',
            0.0, 10.0))
    for name, what in (('thrusts', 'the vehicle applies thrust commands (Hz), held in '
                                   'between (ArduSub: its 50 Hz RC loop)'),
                       ('arm_commands', 'the arm applies joint torque commands (Hz), held in '
                                        "between (the arm bus's command slots)")):
        specs.append(ParameterSpec(f'devices.{name}.rate_hz', 0.0,
                                   f'Rate at which {what}; 0: each command at once.',
                                   0.0, 100000.0))
    specs.append(ParameterSpec(
        'devices.arm_commands.latency_s', 0.0, "From a command slot to the first joint's torque "
        "acting (s), below a slot: the host's turn, its frame on the line; 0: none.", 0.0, 1.0))
    specs.append(ParameterSpec(
        'devices.arm_commands.frame_s', 0.0, "One joint's command frame on the line (s): joint "
        'j acts j frames after the first (a bus sends them in turn); 0: all at once.', 0.0, 1.0))
    return tuple(specs)


SIMULATOR_PARAMETERS += _device_specs()

SPECS_BY_NAME: dict[str, ParameterSpec] = {spec.name: spec for spec in SIMULATOR_PARAMETERS}


@dataclass(frozen=True)
class SimulatorSettings:
    """Validated simulator parameters, in the units the plant and node use."""

    mode: str
    real_time_factor: float
    physics_dt_ns: int
    steps_per_publish: int
    publishes_per_tf: int
    publishes_per_ground_truth: int
    publishes_per_joint_state: int
    lockstep_timeout_s: float
    watchdog_timeout_ns: int
    duration_ns: int
    wall_enabled: bool
    wall_motion_start_force_n: float
    vehicle_pose: np.ndarray
    arm_from_ee_position: bool
    joint_positions: np.ndarray
    ee_position: np.ndarray
    startup: StartupSettings
    devices: DeviceTiming

    @property
    def physics_dt_s(self) -> float:
        """Fixed integration step (s)."""
        return self.physics_dt_ns * 1e-9

    @property
    def wall_period_s(self) -> float:
        """Real time: wall-clock seconds per step (the step over ``real_time_factor``)."""
        return self.physics_dt_s / self.real_time_factor

    @classmethod
    def from_values(cls, values: Mapping[str, Any]) -> SimulatorSettings:
        """Check every value against its spec and derive the settings.

        Args:
            values: Parameter name to value, for every name of ``SIMULATOR_PARAMETERS``.

        Raises:
            SimParameterError: A value is out of range, of the wrong type, or the rates do
                not fit together; the message names the parameter, value and valid range.
        """
        checked: dict[str, Any] = {spec.name: validate_value(spec, values[spec.name])
                                   for spec in SIMULATOR_PARAMETERS}
        physics_hz = float(checked['physics_rate_hz'])
        publish_hz = float(checked['publish_rate_hz'])
        ratio = physics_hz / publish_hz
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            msg = (
                f"parameter 'publish_rate_hz' = {publish_hz:g}: must divide "
                f"physics_rate_hz = {physics_hz:g} into a whole number of steps "
                f'(valid: {physics_hz:g} / n for n = 1, 2, ...)'
            )
            raise SimParameterError(msg)
        dt_ns = round(1e9 / physics_hz)
        if abs(dt_ns - 1e9 / physics_hz) > 1e-6:
            msg = (
                f"parameter 'physics_rate_hz' = {physics_hz:g}: the step must be a whole "
                'number of nanoseconds (e.g. 1000, 2000, 500 Hz)'
            )
            raise SimParameterError(msg)
        tf_hz = float(checked['tf_rate_hz'])
        if tf_hz > publish_hz:
            msg = (
                f"parameter 'tf_rate_hz' = {tf_hz:g} out of range [0, {publish_hz:g}] "
                '(at most publish_rate_hz)'
            )
            raise SimParameterError(msg)
        ground_truth_hz = min(float(checked['ground_truth_rate_hz']), publish_hz)
        joint_hz = float(checked['joint_states_rate_hz'])
        joint_hz = publish_hz if joint_hz == 0.0 else min(joint_hz, publish_hz)
        if joint_hz < publish_hz and checked['mode'] == 'lockstep':
            msg = (f"parameter 'joint_states_rate_hz' = {joint_hz:g}: below publish_rate_hz = "
                   f'{publish_hz:g} only in real time (in lockstep every state is answered '
                   'with joint_states)')
            raise SimParameterError(msg)
        return cls(
            mode=str(checked['mode']),
            real_time_factor=float(checked['real_time_factor']),
            physics_dt_ns=dt_ns,
            steps_per_publish=round(ratio),
            publishes_per_tf=max(1, round(publish_hz / tf_hz)) if tf_hz > 0.0 else 0,
            publishes_per_ground_truth=max(1, round(publish_hz / ground_truth_hz)),
            publishes_per_joint_state=max(1, round(publish_hz / joint_hz)),
            lockstep_timeout_s=float(checked['lockstep_timeout_s']),
            watchdog_timeout_ns=round(float(checked['watchdog_timeout_s']) * 1e9),
            duration_ns=round(float(checked['duration_s']) * 1e9),
            wall_enabled=bool(checked['wall_enabled']),
            wall_motion_start_force_n=float(checked['wall_motion_start_force_n']),
            vehicle_pose=np.array(checked['initial.vehicle_pose'], dtype=float),
            arm_from_ee_position=checked['initial.arm'] == 'ee_position',
            joint_positions=np.array(checked['initial.joint_positions'], dtype=float),
            ee_position=np.array(checked['initial.ee_position'], dtype=float),
            startup=StartupSettings(bool(checked['startup.hold']),
                                    round(float(checked['startup.timeout_s']) * 1e9),
                                    tuple(checked['startup.nodes']),
                                    str(checked['startup.recorder']),
                                    str(checked['startup.mission']),
                                    recorder_topics(checked['startup.recorder_topics'])),
            devices=DeviceTiming.from_values(checked),
        )


def recorder_topics(names: Sequence[str]) -> tuple[str, ...]:
    """``startup.recorder_topics`` as `StartupSettings` takes it: () for every state topic.

    >>> recorder_topics(['*'])
    ()
    >>> recorder_topics(['imu', '/clock'])
    ('imu', '/clock')
    """
    return () if '*' in names else tuple(names)


def validate_value(spec: ParameterSpec, value: Any) -> Value:
    """Check one value against its spec.

    Returns:
        The value, floats for float parameters, a list of floats for arrays.

    Raises:
        SimParameterError: Naming the parameter, the value and the valid range.
    """
    default = spec.default
    if isinstance(default, bool):
        if not isinstance(value, bool):
            raise SimParameterError(_message(spec, value, 'expected a bool'))
        return value
    if isinstance(default, str):
        if not isinstance(value, str) or (spec.choices and value not in spec.choices):
            raise SimParameterError(_message(spec, value, 'invalid value'))
        return value
    if isinstance(default, list) and all(isinstance(v, str) for v in default):
        if isinstance(value, str | bytes) or not isinstance(value, Sequence) or not all(
                isinstance(v, str) and v for v in value):
            raise SimParameterError(_message(spec, value, 'expected an array of names'))
        return list(value)
    if isinstance(default, list):
        if isinstance(value, str | bytes) or not isinstance(value, Sequence | np.ndarray):
            raise SimParameterError(_message(spec, value, 'expected an array of numbers'))
        items = [float(v) for v in value]
        if spec.length is not None and len(items) != spec.length:
            raise SimParameterError(_message(spec, list(items), 'wrong length'))
        for item in items:
            _check_number(spec, item, items)
        return items
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise SimParameterError(_message(spec, value, 'expected a number'))
    if isinstance(default, int) and not isinstance(value, int):
        raise SimParameterError(_message(spec, value, 'expected an integer'))
    _check_number(spec, float(value), value)
    return value if isinstance(default, int) else float(value)


def _check_number(spec: ParameterSpec, number: float, shown: Any) -> None:
    """Check finiteness and range of one number."""
    if not math.isfinite(number):
        raise SimParameterError(_message(spec, shown, 'not a finite number'))
    if spec.min_value is not None and number < spec.min_value:
        raise SimParameterError(_message(spec, shown, 'out of range'))
    if spec.max_value is not None and number > spec.max_value:
        raise SimParameterError(_message(spec, shown, 'out of range'))


def _message(spec: ParameterSpec, value: Any, problem: str) -> str:
    """Error message naming the parameter, the value and the valid range."""
    return f'parameter {spec.name!r} = {value!r}: {problem}; valid: {spec.range_text()}'


def default_joint_positions(joint_positions: np.ndarray, n_joints: int) -> np.ndarray:
    """``initial.joint_positions``, or zeros (n,) where it was left at the paper arm's default.

    The default [0, 0.4, -0.8] is the elbow-up guess of the paper's 3-joint arm; a robot with
    another joint count that leaves it alone starts from zeros (a guess for ``ee_position``).
    A value given explicitly is returned as it is (the plant checks its length).

    >>> default_joint_positions(np.array([0.0, 0.4, -0.8]), 4).tolist()
    [0.0, 0.0, 0.0, 0.0]
    >>> default_joint_positions(np.array([0.0, 0.4, -0.8]), 3).tolist()
    [0.0, 0.4, -0.8]
    """
    default = np.array(SPECS_BY_NAME['initial.joint_positions'].default, dtype=float)
    if joint_positions.shape != (n_joints,) and np.array_equal(joint_positions, default):
        return np.zeros(n_joints)
    return joint_positions
