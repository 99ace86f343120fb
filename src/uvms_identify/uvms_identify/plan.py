"""``uvms identify plan``: the identification experiments as scenario files.

No input of the graph commands thrust open loop (the controller closes the loop on the end
effector), so each experiment drives the thrusters through the thruster allocator's fault
injection (the scenario's ``faults`` key, ``uvms_thrusters.thruster_faults``): every thruster
is ``stuck`` at a thrust from t = 0, and a new ``stuck`` entry at each change of level sets
the next thrust. The thrusts are ``level * f_axis`` with ``f_axis`` the least-norm thrusts of
a unit wrench on the axis (the pseudo-inverse of the thruster configuration matrix), scaled
to ``THRUST_FRACTION`` of the smallest thrust limit; the thruster model then follows them as
a real ESC would (its lag included). The controller stays active (the safety supervisor on);
its commands reach no thruster, and it keeps the arm where it can. What the robot records
(IMU, DVL, depth, joint states, the thrusts sent) is what ``uvms identify fit`` reads.

Per axis one experiment of ``DURATION_S``: steps of alternating sign and rising amplitude
(steady speeds for the quadratic damping, each followed by the next or a free decay), a
chirp about a static offset (+ then -), and a free decay at the end.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml
from numpy.typing import NDArray

from uvms_identify.regressor import AXES
from uvms_identify.robot_data import RobotData

FloatArray = NDArray[np.float64]

THRUST_FRACTION = 0.8
STEP_LEVELS = (0.3, -0.3, 0.6, -0.6, 1.0, -1.0, 0.45, -0.45)
STEP_S = 2.5
DECAY_S = 3.0
CHIRP_S = 16.0
CHIRP_OFFSET = 0.5
CHIRP_AMPLITUDE = 0.4
CHIRP_HZ = (0.1, 0.6)
CHIRP_STEP_S = 0.2
FINAL_DECAY_S = 4.0
DURATION_S = len(STEP_LEVELS) * STEP_S + DECAY_S + CHIRP_S + FINAL_DECAY_S
#: Largest expected excursion per axis (m, m, m, rad, rad, rad): heave within 1.2 m (the
#: DVL keeps bottom lock and the vehicle the water), roll and pitch within 20 deg of level;
#: surge and sway are bounded by the thrust (stated in the plan).
MAX_EXCURSION = (math.inf, math.inf, 1.2, 0.35, 0.35, math.inf)
#: Largest expected speed per axis (m/s, rad/s): yaw within 1 rad/s (the AHRS and the DVL's
#: lever arm stay well behaved).
MAX_SPEED = (math.inf, math.inf, math.inf, math.inf, math.inf, 1.0)
START_DEPTH_M = 2.5
SEABED_DEPTH_M = 4.5
#: What the recorder records: the robot's own sensors and commands; the ground truth
#: odometry only for the acceptance check (the fit never reads it). ``wrench``, ``ee_pose``
#: and ``contact`` too: `uvms launch` starts the simulator only once its recorder subscribes
#: to every state topic it publishes (``startup.recorder``); without them a plan's scenario
#: held the twin stand at t = 0 until the ArduSub bridge gave up (no HEARTBEAT in 30 s).
RECORDED_TOPICS = [
    '/clock:rosgraph_msgs/msg/Clock',
    'joint_states:sensor_msgs/msg/JointState',
    'imu:sensor_msgs/msg/Imu',
    'dvl:geometry_msgs/msg/TwistWithCovarianceStamped',
    'depth:geometry_msgs/msg/PoseWithCovarianceStamped',
    'command/actuators:uvms_msgs/msg/ActuatorCommand',
    'thrusters/state:uvms_msgs/msg/ThrusterState',
    'odometry:nav_msgs/msg/Odometry',
    'wrench:geometry_msgs/msg/WrenchStamped',
    'ee_pose:geometry_msgs/msg/PoseStamped',
    'contact:uvms_msgs/msg/ContactState',
]


@dataclass(frozen=True)
class Experiment:
    """One planned experiment.

    Attributes:
        axis: Index of the excited axis (0 surge .. 5 yaw).
        times_s: Start time of each level (L,) (s).
        levels: Generalized force of each level (L,) (N or N m).
        thrusts_n: Thrusts of each level (L, p) (N).
        excursion: Expected largest displacement on the axis (m or rad).
        top_speed: Expected largest speed on the axis (m/s or rad/s).
    """

    axis: int
    times_s: FloatArray
    levels: FloatArray
    thrusts_n: FloatArray
    excursion: float
    top_speed: float

    @property
    def name(self) -> str:
        """Scenario name, e.g. ``identify_surge``."""
        return f'identify_{AXES[self.axis]}'


def axis_thrusts(robot: RobotData, axis: int) -> tuple[FloatArray, float]:
    """Thrusts of a unit wrench on ``axis`` (p,) and the largest wrench within the limits."""
    wrench = np.zeros(6)
    wrench[axis] = 1.0
    unit_thrusts = np.linalg.pinv(robot.thrust_matrix) @ wrench
    peak = float(np.max(np.abs(unit_thrusts) / robot.max_thrust_n))
    return unit_thrusts, THRUST_FRACTION / peak


def signal(maximum: float) -> tuple[FloatArray, FloatArray]:
    """Level start times (s) and generalized forces of one experiment."""
    times: list[float] = []
    levels: list[float] = []
    t = 0.0
    for level in STEP_LEVELS:
        times.append(t)
        levels.append(level * maximum)
        t += STEP_S
    times.append(t)
    levels.append(0.0)
    t += DECAY_S
    phase = 0.0
    f0, f1 = CHIRP_HZ
    steps = round(CHIRP_S / CHIRP_STEP_S)
    for k in range(steps):
        fraction = k / steps
        frequency = f0 + (f1 - f0) * fraction
        sign = 1.0 if fraction < 0.5 else -1.0
        times.append(t)
        levels.append(maximum * (sign * CHIRP_OFFSET + CHIRP_AMPLITUDE * math.sin(phase)))
        phase += 2.0 * math.pi * frequency * CHIRP_STEP_S
        t += CHIRP_STEP_S
    times.append(t)
    levels.append(0.0)
    return np.array(times), np.array(levels)


def expected_motion(robot: RobotData, axis: int, times_s: FloatArray, levels: FloatArray,
                    rigid_inertia: float, restoring: float) -> tuple[float, float]:
    """Largest excursion and speed on ``axis`` by the robot folder's model, one axis alone.

    ``(m + A) v_dot = tau - d_l v - d_q |v| v - k x`` integrated at 1 ms; ``restoring`` is k
    (0 for surge, sway, yaw; the hull's net buoyancy is assumed trimmed for heave).
    """
    prior = robot.prior_theta()
    inertia = rigid_inertia + prior[axis]
    linear, quadratic = prior[6 + axis], prior[12 + axis]
    dt = 1e-3
    x = v = 0.0
    excursion = top = 0.0
    for t in np.arange(0.0, DURATION_S, dt):
        tau = float(levels[np.searchsorted(times_s, t, side='right') - 1])
        v += dt * (tau - linear * v - quadratic * abs(v) * v - restoring * x) / inertia
        x += dt * v
        excursion = max(excursion, abs(x))
        top = max(top, abs(v))
    return excursion, top


def plan(robot: RobotData, rigid_inertia: FloatArray, restoring: FloatArray) -> list[Experiment]:
    """One experiment per axis.

    Args:
        robot: The robot folder.
        rigid_inertia: Diagonal of the rigid-body mass matrix at rest (6,) (kg, kg m^2).
        restoring: Restoring stiffness per axis (6,) (N/m, N m/rad): roll and pitch.
    """
    experiments = []
    for axis in range(6):
        unit_thrusts, maximum = axis_thrusts(robot, axis)
        for _ in range(20):  # shrink the amplitude until the axis' limits hold
            times, levels = signal(maximum)
            excursion, top = expected_motion(robot, axis, times, levels,
                                             float(rigid_inertia[axis]), float(restoring[axis]))
            ratio = max(excursion / MAX_EXCURSION[axis], top / MAX_SPEED[axis])
            if ratio <= 1.0:
                break
            maximum *= 0.9 / ratio
        experiments.append(Experiment(axis, times, levels, np.outer(levels, unit_thrusts),
                                      excursion, top))
    return experiments


def scenario(robot: RobotData, experiment: Experiment, robot_reference: str,
             joint_positions: FloatArray) -> dict[str, object]:
    """The scenario file's mapping of one experiment (config/scenarios format).

    The vehicle starts level at ``START_DEPTH_M`` with the arm at ``joint_positions`` (the
    robot folder's start.yaml guess).
    """
    axis = AXES[experiment.axis]
    unit = 'm' if experiment.axis < 3 else 'rad'
    faults = []
    previous = np.full(experiment.thrusts_n.shape[1], np.nan)
    for t, thrusts in zip(experiment.times_s, experiment.thrusts_n, strict=True):
        for index, thrust in enumerate(thrusts):
            value = round(float(thrust), 4)
            if value != previous[index]:
                faults.append({'index': index, 'kind': 'stuck', 'value': value,
                               'at_s': round(float(t), 4)})
                previous[index] = value
    peak = float(np.abs(experiment.levels).max())
    force_unit = 'N' if experiment.axis < 3 else 'N m'
    return {
        'name': experiment.name,
        'description': (
            f'uvms identify plan: {axis} of robot {robot.name}, open loop through the '
            f'thrusters held (stuck) at planned thrusts: steps of alternating sign up to '
            f'{peak:.3g} {force_unit}, a chirp {CHIRP_HZ[0]:g}-{CHIRP_HZ[1]:g} Hz about a '
            f'static offset, free decays. Expected (robot folder model, axis alone): '
            f'excursion {experiment.excursion:.2f} {unit}, top speed '
            f'{experiment.top_speed:.2f} {unit}/s. Thrusts within {THRUST_FRACTION:.0%} of '
            "each thruster's limit."),
        'robot': robot_reference,
        'duration_s': float(DURATION_S),
        'seed': 1,
        'simulator': {
            'wall_enabled': False,
            'navigation': {'enabled': True},
            'world': {'seabed_depth_m': SEABED_DEPTH_M},
            'initial': {'vehicle_pose': [0.0, 0.0, START_DEPTH_M, 0.0, 0.0, 0.0],
                        'arm': 'joint_positions',
                        'joint_positions': [float(a) for a in joint_positions]},
        },
        # The stuck thrusters are the experiment, not a fault: detection would only flag them.
        'thruster_allocator': {'fault_detection': {'enabled': False}},
        'recorder': {'topics': list(RECORDED_TOPICS)},
        'faults': {'thrusters': faults},
    }


def write_plan(robot: RobotData, experiments: list[Experiment], out: Path,
               robot_reference: str, joint_positions: FloatArray) -> list[Path]:
    """Write one scenario file per experiment and a README.md; returns the scenario paths."""
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    lines = [f'# Identification experiments for robot {robot.name}', '',
             'Run each with `uvms run FILE --output FILE.mcap` (simulator) or `uvms launch FILE '
             '--hardware HW.yaml` (robot), then `uvms identify fit *.mcap --robot ROBOT --out '
             'DIR`.', '', '| scenario | axis | peak wrench | expected excursion | expected top '
             'speed | duration (s) |', '| --- | --- | --- | --- | --- | --- |']
    for experiment in experiments:
        data = scenario(robot, experiment, robot_reference, joint_positions)
        path = out / f'{experiment.name}.yaml'
        text = ('# Scenario file (schema: docs/running.md, uvms_scenarios/scenario.py), '
                'written by '
                '`uvms identify plan`.\n' + yaml.safe_dump(data, sort_keys=False, width=99))
        path.write_text(text, encoding='utf-8')
        paths.append(path)
        unit = 'm' if experiment.axis < 3 else 'rad'
        force_unit = 'N' if experiment.axis < 3 else 'N m'
        lines.append(f'| {path.name} | {AXES[experiment.axis]} | '
                     f'{np.abs(experiment.levels).max():.3g} {force_unit} | '
                     f'{experiment.excursion:.2f} {unit} | {experiment.top_speed:.2f} {unit}/s | '
                     f'{DURATION_S:g} |')
    (out / 'README.md').write_text('\n'.join(lines) + '\n', encoding='utf-8')
    return paths
