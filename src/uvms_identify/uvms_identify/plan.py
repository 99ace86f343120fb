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

Per axis one experiment of ``DURATION_S`` (``uvms_identify.plan_signals``): steps and a
chirp about a static offset, free decays between; heave (with ``level`` surge and sway too) by
doublets that return the vehicle to its start (steady speeds for the quadratic damping
within a small excursion: heave at 0.45 m/s within its 1.2 m bound, where the steps reached
0.22 m/s, too slow to tell |w| w from w through the twin stand: -28 %) and a chirp. An
experiment by doublets is **trimmed** and holds the arm in joint space, as ``level`` does
(below): the default plan's heave is the level plan's.

**Level** (``level=True``, ``uvms identify plan --level``). Every level adds the **trim**:
the thrusts whose wrench cancels the static wrench of weight and buoyancy at level with the
arm at its start pose (the robot folder's model); without it the shipped BlueROV2 Heavy
with the Alpha 5 at its start pose settles at 0.19 rad pitch with every thruster at 0 N.
Surge, sway and heave run as doublets, surge and sway below the speed where the hull's
**Munk moment** (the added mass' (A_w - A_u) u w, resp. (A_w - A_v) v w, which turns the
hull across the flow) outgrows the restoring moment of weight and buoyancy (k theta):
``MUNK_MARGIN`` of
sqrt(k / (A_w - A_u)); above it the hull is statically unstable in pitch (roll). Not the
default: the controller's arm, reaching for its world-fixed hold point while the vehicle
moves, still tilts the vehicle past 0.35 rad (docs/identification.md, "Why the vehicle
tumbles"), the acceptance's fit identifies pitch less well without the old tumbling, and the
doublet heave without the trim and the joint hold, with the default's other experiments,
moved the fit's surge added mass to -18 % (a tumbling heave run, deterministic in lockstep;
trimmed and held, as now, -6.0 % and pitch within 0.17 rad).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml
from numpy.typing import NDArray

from uvms_identify.plan_signals import (
    CHIRP_HZ,
    DURATION_S,
    HEAVE_CHIRP_HZ,
    doublets,
    steps_and_chirp,
)
from uvms_identify.regressor import AXES
from uvms_identify.robot_data import RobotData

FloatArray = NDArray[np.float64]

THRUST_FRACTION = 0.8
#: Largest expected excursion per axis (m, m, m, rad, rad, rad): heave within 1.2 m (the
#: DVL keeps bottom lock and the vehicle the water), roll and pitch within 20 deg of level;
#: surge and sway are bounded by the thrust (stated in the plan).
MAX_EXCURSION = (math.inf, math.inf, 1.2, 0.35, 0.35, math.inf)
#: Largest expected speed per axis (m/s, rad/s): heave within 0.45 m/s (full thrust, 0.73
#: m/s, made the controller's arm, which chases its world-fixed hold point, diverge in the
#: simulator: a joint rate over 50 rad/s after 8 s), yaw within 1 rad/s (the AHRS and the
#: DVL's lever arm stay well behaved).
MAX_SPEED = (math.inf, math.inf, 0.45, math.inf, math.inf, 1.0)
#: Surge and sway at most this fraction of the speed where the Munk moment equals the
#: restoring moment (module docstring).
MUNK_MARGIN = 0.8
#: Axes excited by doublets that return to the start (plan_signals.doublets), trimmed and
#: with the arm held: by default heave, with ``level`` surge, sway and heave.
DOUBLET_AXES = (2,)
LEVEL_DOUBLET_AXES = (0, 1, 2)
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
        trimmed: Every level holds the trim of weight and buoyancy (``plan``'s trim_wrench).
        doublets: Excited by ``plan_signals.doublets`` (else steps and a chirp).
    """

    axis: int
    times_s: FloatArray
    levels: FloatArray
    thrusts_n: FloatArray
    excursion: float
    top_speed: float
    trimmed: bool = False
    doublets: bool = False

    @property
    def name(self) -> str:
        """Scenario name, e.g. ``identify_surge``."""
        return f'identify_{AXES[self.axis]}'


def axis_thrusts(robot: RobotData, axis: int,
                 trim_thrusts: FloatArray | None = None) -> tuple[FloatArray, float]:
    """Thrusts of a unit wrench on ``axis`` (p,) and the largest wrench within the limits.

    With ``trim_thrusts`` (p,) the largest wrench leaves each thruster room for its trim.
    """
    wrench = np.zeros(6)
    wrench[axis] = 1.0
    unit_thrusts = np.linalg.pinv(robot.thrust_matrix) @ wrench
    trim = np.zeros_like(unit_thrusts) if trim_thrusts is None else np.abs(trim_thrusts)
    room = THRUST_FRACTION * robot.max_thrust_n - trim
    used = np.abs(unit_thrusts) > 1e-9
    return unit_thrusts, float(np.min(room[used] / np.abs(unit_thrusts[used])))


def trim_thrusts(robot: RobotData, trim_wrench: FloatArray) -> FloatArray:
    """Least-norm thrusts (p,) of the trim wrench (6,) (heave, roll, pitch entries used)."""
    wrench = np.zeros(6)
    wrench[2:5] = np.asarray(trim_wrench, float)[2:5]
    thrusts: FloatArray = np.linalg.pinv(robot.thrust_matrix) @ wrench
    return thrusts


def speed_limits(robot: RobotData, restoring: FloatArray) -> FloatArray:
    """Largest planned speed per axis (6,): ``MAX_SPEED``, surge and sway below Munk's.

    Surge: ``MUNK_MARGIN`` sqrt(k_pitch / (A_w - A_u)), sway: with k_roll and A_w - A_v (no
    limit where the heave added mass is the smaller: the Munk moment then restores).
    """
    limits = np.array(MAX_SPEED, float)
    added = robot.prior_theta()[:6]
    for axis, tilt in ((0, 4), (1, 3)):
        difference = float(added[2] - added[axis])
        if difference > 0.0:
            critical = math.sqrt(max(float(restoring[tilt]), 0.0) / difference)
            limits[axis] = min(limits[axis], MUNK_MARGIN * critical)
    return limits


def expected_motion(robot: RobotData, axis: int, times_s: FloatArray, levels: FloatArray,
                    rigid_inertia: float, restoring: float) -> tuple[float, float]:
    """Largest excursion and speed on ``axis`` by the robot folder's model, one axis alone.

    ``(m + A) v_dot = tau - d_l v - d_q |v| v - k x`` integrated at 1 ms; ``restoring`` is k
    (0 for surge, sway, yaw; the hull's net buoyancy is assumed trimmed for heave).
    """
    prior = robot.prior_theta()
    inertia = rigid_inertia + float(prior[axis])
    linear, quadratic = float(prior[6 + axis]), float(prior[12 + axis])
    dt = 1e-3
    grid = np.arange(0.0, DURATION_S, dt)
    taus = levels[np.searchsorted(times_s, grid, side='right') - 1].tolist()
    x = v = 0.0
    excursion = top = 0.0
    for tau in taus:
        v += dt * (tau - linear * v - quadratic * abs(v) * v - restoring * x) / inertia
        x += dt * v
        excursion = max(excursion, abs(x))
        top = max(top, abs(v))
    return excursion, top


def plan(robot: RobotData, rigid_inertia: FloatArray, restoring: FloatArray,
         trim_wrench: FloatArray | None = None, *, level: bool = False) -> list[Experiment]:
    """One experiment per axis.

    Args:
        robot: The robot folder.
        rigid_inertia: Diagonal of the rigid-body mass matrix at rest (6,) (kg, kg m^2).
        restoring: Restoring stiffness per axis (6,) (N/m, N m/rad): roll and pitch.
        trim_wrench: Static wrench of weight and buoyancy at level (6,) (N, N m)
            (``known_terms.trim_wrench``), added to every level of a trimmed experiment: with
            ``level`` all, else those by doublets; none: no trim.
        level: Surge and sway by doublets below the Munk speed (``speed_limits``), every
            experiment trimmed, the arm held in joint space (module docstring).
    """
    limits = speed_limits(robot, restoring) if level else np.array(MAX_SPEED, float)
    doublet_axes = LEVEL_DOUBLET_AXES if level else DOUBLET_AXES
    untrimmed = np.zeros(robot.thrust_matrix.shape[1])
    full_trim = untrimmed if trim_wrench is None else trim_thrusts(robot, trim_wrench)
    experiments = []
    for axis in range(6):
        trimmed = trim_wrench is not None and (level or axis in doublet_axes)
        trim = full_trim if trimmed else untrimmed
        unit_thrusts, maximum = axis_thrusts(robot, axis, trim)
        signal = doublets if axis in doublet_axes else steps_and_chirp
        for _ in range(20):  # shrink the amplitude until the axis' limits hold
            times, levels = signal(maximum)
            excursion, top = expected_motion(robot, axis, times, levels,
                                             float(rigid_inertia[axis]), float(restoring[axis]))
            ratio = max(excursion / MAX_EXCURSION[axis], top / limits[axis])
            if ratio <= 1.0:
                break
            maximum *= (0.9 if ratio > 1.05 else 0.99) / ratio
        experiments.append(Experiment(axis, times, levels,
                                      np.outer(levels, unit_thrusts) + trim[None, :],
                                      excursion, top, trimmed, signal is doublets))
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
    trimmed = (', every level with the trim of weight and buoyancy at level, the arm held in '
               'joint space' if experiment.trimmed else '')
    shape = (f'doublets back to the start and a chirp {HEAVE_CHIRP_HZ[0]:g}-'
             f'{HEAVE_CHIRP_HZ[1]:g} Hz about zero' if experiment.doublets else
             f'steps of alternating sign, a chirp {CHIRP_HZ[0]:g}-{CHIRP_HZ[1]:g} Hz about a '
             'static offset')
    force_unit = 'N' if experiment.axis < 3 else 'N m'
    return {
        'name': experiment.name,
        'description': (
            f'uvms identify plan: {axis} of robot {robot.name}, open loop through the '
            f'thrusters held (stuck) at planned thrusts up to {peak:.3g} {force_unit}: '
            f'{shape}, free decays{trimmed}. Expected (robot folder model, axis alone): '
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
        # Level: the arm held where it is, not reaching for a world-fixed point as the vehicle
        # moves (its weight and reactions tilt the vehicle: core/task/joint_hold.py).
        **({'controller': {'arm': {'hold_in_joint_space': True}}} if experiment.trimmed else {}),
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
