"""What the robot itself recorded, read from an MCAP and put on one time grid.

Read (suffixes of the topic names, so any namespace works): ``/imu`` (attitude and rates),
``/dvl`` (velocity over ground in dvl_link), ``/joint_states`` (the arm's encoders),
``/command/actuators`` (the thrusts sent) and, optionally, ``/depth`` and the estimate
``/odometry/filtered``. Never the simulator's ground truth (``/odometry``, ``/contact``).
Times are the messages' header stamps.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from uvms_recording.errors import RecordingError
from uvms_recording.mcap_reader import open_recording
from uvms_recording.typestore import uvms_typestore

from uvms_identify.errors import IdentifyError
from uvms_identify.robot_data import RobotData
from uvms_identify.signals import (
    euler_zyx,
    quaternion_to_matrix,
    resample,
    smooth_and_differentiate,
)

FloatArray = NDArray[np.float64]

#: Required topic suffixes and what they are, for the refusal's one line.
REQUIRED = {
    '/imu': 'IMU (attitude, rates)',
    '/joint_states': 'arm joint states',
    '/command/actuators': 'thrust commands',
}
VELOCITY_TOPICS = {'dvl': ('/dvl', 'DVL velocity'),
                   'estimate': ('/odometry/filtered', 'the estimate (odometry/filtered)')}
#: Ground-truth topics, never read.
GROUND_TRUTH = ('/uvms/odometry', '/uvms/contact')
MIN_DURATION_S = 5.0
MIN_SPEED = 0.01  # m/s or rad/s: below it on every axis the vehicle did not move
MIN_THRUST_STD_N = 0.1  # N: a thrust that varies less excites nothing
#: Longest time between two messages that is not a gap (s). The velocity: a DVL reports at
#: 2-15 Hz by altitude; a longer silence is a lost bottom lock.
MAX_VELOCITY_INTERVAL_S = 0.6
#: The IMU, the joint states and the thrusts sent (at 50-500 Hz): a longer silence is
#: messages lost (a recorder that fell behind keeps bursts of them out). Interpolated across,
#: such a hole smooths the accelerations the thrusts are balanced against and biases the
#: added mass low: twin stand recordings that lost 0.05-0.3 s bursts of their IMU put the yaw
#: added mass at 0 (0.28 kg m^2 from the same runs with every message, truth 0.30).
MAX_SAMPLE_INTERVAL_S = 0.2
MIN_SEGMENT_S = 2.0  # s: shorter stretches between gaps are left out


@dataclass
class Series:
    """One recording on a uniform grid.

    Attributes:
        source: The recording.
        t_s: Grid times (N,) (s).
        nu: Body velocities (N, 6) (m/s, rad/s), smoothed.
        nu_dot: Their derivatives (N, 6).
        rpy: Attitude (N, 3) (rad); ``gravity_body``: R^T e_z (N, 3).
        joints, joint_rates, joint_accelerations: The arm (N, n).
        tau: Thrust wrench in base_link_frd (N, 6) (N, N m).
        thrusts: The thrusts (N, p) (N).
        depth_m: Depth (N,) (m), NaN without a depth topic.
        valid: Where every signal is measured (N,): False within the smoothing window of a
            gap of the velocity topic (a DVL without bottom lock) or of the IMU, the joint
            states or the thrusts (messages lost on the way to the recording).
        joint_torques: The arm's torques commanded (``command/actuators``) (N, n) (N m),
            smoothed as the rest; (N, 0) when the recording holds none.
        gaps_s: Per signal with gaps (its name as in the refusals), the time of the grid
            in them (s).
    """

    source: Path
    t_s: FloatArray
    nu: FloatArray
    nu_dot: FloatArray
    rpy: FloatArray
    gravity_body: FloatArray
    joints: FloatArray
    joint_rates: FloatArray
    joint_accelerations: FloatArray
    tau: FloatArray
    thrusts: FloatArray
    depth_m: FloatArray
    valid: NDArray[np.bool_]
    joint_torques: FloatArray
    gaps_s: dict[str, float] = field(default_factory=dict)

    def window(self, mask: NDArray[np.bool_]) -> Series:
        """The samples where ``mask`` holds."""
        return Series(self.source, *(getattr(self, f)[mask] for f in (
            't_s', 'nu', 'nu_dot', 'rpy', 'gravity_body', 'joints', 'joint_rates',
            'joint_accelerations', 'tau', 'thrusts', 'depth_m', 'valid', 'joint_torques')),
            gaps_s=self.gaps_s)


def gaps_text(gaps_s: dict[str, float]) -> str:
    """The time in gaps per signal, worded: ``IMU (attitude, rates) 1.6 s, ...`` or ``none``."""
    return ', '.join(f'{what} {seconds:.1f} s' for what, seconds in gaps_s.items()) or 'none'


def gap_mask(sample_t_s: FloatArray, grid_s: FloatArray,
             max_interval_s: float) -> NDArray[np.bool_]:
    """The grid points in a gap (N,).

    A gap: two consecutive samples (times ``sample_t_s``) farther apart than
    ``max_interval_s``.
    """
    after = np.clip(np.searchsorted(sample_t_s, grid_s, side='right'), 1, sample_t_s.size - 1)
    result: NDArray[np.bool_] = sample_t_s[after] - sample_t_s[after - 1] > max_interval_s
    return result


def _stamp(message: object) -> float:
    stamp = message.header.stamp  # type: ignore[attr-defined]
    return float(stamp.sec) + 1e-9 * float(stamp.nanosec)


def _find(topics: list[str], suffix: str) -> str | None:
    for topic in topics:
        if topic.endswith(suffix) and topic not in GROUND_TRUTH:
            return topic
    return None


def read_series(path: str | Path, robot: RobotData, *, velocity: str = 'dvl',
                rate_hz: float = 50.0, window_s: float = 0.6) -> Series:
    """The recording at ``path`` as a ``Series``.

    Raises:
        IdentifyError: One line naming the file and what is missing: an unreadable file, a
            topic not recorded (or without messages), a recording too short, or a vehicle
            that did not move.
    """
    path = Path(path)
    try:
        recording = open_recording(path)
    except RecordingError as exc:
        raise IdentifyError(f'{path}: {exc}') from exc
    names = [t for t, info in recording.topics.items() if info.message_count > 0]
    wanted = {**REQUIRED, VELOCITY_TOPICS[velocity][0]: VELOCITY_TOPICS[velocity][1]}
    found: dict[str, str] = {}
    missing = []
    for suffix, what in wanted.items():
        topic = _find(names, suffix)
        if topic is None:
            missing.append(f'{suffix.lstrip("/")} ({what})')
        else:
            found[suffix] = topic
    if missing:
        hint = (' (the scenarios of `uvms identify plan` record them: navigation.enabled and '
                "the recorder's topics)") \
            if any('imu' in m or 'dvl' in m for m in missing) else ''
        raise IdentifyError(f'{path}: not in the recording: {", ".join(missing)}{hint}')
    depth_topic = _find(names, '/depth')
    topic_of = {topic: suffix for suffix, topic in found.items()}
    if depth_topic:
        topic_of[depth_topic] = '/depth'
    rows: dict[str, list[tuple[float, list[float]]]] = {s: [] for s in topic_of.values()}
    torque_rows: list[tuple[float, list[float]]] = []
    typestore = uvms_typestore()
    try:
        for message in recording.messages(topic_of):
            msg = typestore.deserialize_cdr(message.data, message.type_name)
            suffix = topic_of[message.topic]
            t = _stamp(msg)
            if suffix == '/imu':
                o, r = msg.orientation, msg.angular_velocity
                rows[suffix].append((t, [o.x, o.y, o.z, o.w, r.x, r.y, r.z]))
            elif suffix == '/dvl':
                v = msg.twist.twist.linear
                rows[suffix].append((t, [v.x, v.y, v.z]))
            elif suffix == VELOCITY_TOPICS['estimate'][0]:
                v, r = msg.twist.twist.linear, msg.twist.twist.angular
                rows[suffix].append((t, [v.x, v.y, v.z, r.x, r.y, r.z]))
            elif suffix == '/joint_states':
                rows[suffix].append((t, [*msg.position, *msg.velocity]))
            elif suffix == '/command/actuators':
                rows[suffix].append((t, list(msg.thrust)))
                torque_rows.append((t, list(msg.joint_torques)))
            else:
                rows[suffix].append((t, [msg.pose.pose.position.z]))
    except RecordingError as exc:
        raise IdentifyError(f'{path}: {exc}') from exc

    def arrays(suffix: str) -> tuple[FloatArray, FloatArray]:
        # Rows of another length (a message of another robot on the same topic) are left out.
        lengths = [len(row[1]) for row in rows[suffix]]
        usual = max(set(lengths), key=lengths.count)
        data = [row for row, length in zip(rows[suffix], lengths, strict=True)
                if length == usual]
        t = np.array([row[0] for row in data])
        values = np.array([row[1] for row in data], float)
        order = np.argsort(t, kind='stable')
        t, values = t[order], values[order]
        keep = np.r_[True, np.diff(t) > 0.0]
        return t[keep], values[keep]

    series = {s: arrays(s) for s in rows}
    start = max(float(series[s][0][0]) for s in found)
    end = min(float(series[s][0][-1]) for s in found)
    if end - start < MIN_DURATION_S:
        raise IdentifyError(f'{path}: too short: {max(end - start, 0.0):.1f} s of '
                            f'{", ".join(s.lstrip("/") for s in found)} together, at least '
                            f'{MIN_DURATION_S:g} s needed')
    dt = 1.0 / rate_hz
    grid = np.arange(start, end, dt)
    imu_t, imu = series['/imu']
    rotations = quaternion_to_matrix(resample(imu_t, imu[:, :4], grid))
    rates = resample(imu_t, imu[:, 4:], grid)
    velocity_t = series[VELOCITY_TOPICS[velocity][0]][0]
    if velocity == 'dvl':
        dvl_t, dvl = series['/dvl']
        rates_at_dvl = resample(imu_t, imu[:, 4:], dvl_t)
        linear = dvl @ robot.dvl_rotation.T - np.cross(rates_at_dvl, robot.dvl_position_m)
        nu_raw = np.column_stack([resample(dvl_t, linear, grid), rates])
    else:
        est_t, est = series[VELOCITY_TOPICS['estimate'][0]]
        nu_raw = resample(est_t, est, grid)
    nu, nu_dot = smooth_and_differentiate(nu_raw, dt, window_s)
    joint_t, joint = series['/joint_states']
    n_joints = joint.shape[1] // 2
    joints = resample(joint_t, joint[:, :n_joints], grid)
    joint_rates, joint_accelerations = smooth_and_differentiate(
        resample(joint_t, joint[:, n_joints:], grid), dt, window_s)
    thrust_t, thrust = series['/command/actuators']
    if thrust.shape[1] != robot.thrust_matrix.shape[1]:
        raise IdentifyError(f'{path}: command/actuators has {thrust.shape[1]} thrusts, robot '
                            f'{robot.name} has {robot.thrust_matrix.shape[1]} thrusters')
    # The thrusts pass the same Savitzky-Golay smoothing as the velocities whose derivative
    # they balance: a force against a smoothed acceleration would read as extra mass.
    thrusts = smooth_and_differentiate(resample(thrust_t, thrust, grid), dt, window_s)[0]
    torque_t = np.array([row[0] for row in torque_rows if len(row[1]) == n_joints])
    if n_joints and torque_t.size > 3:
        torque = np.array([row[1] for row in torque_rows if len(row[1]) == n_joints], float)
        order = np.argsort(torque_t, kind='stable')
        torque_t, torque = torque_t[order], torque[order]
        keep_torque = np.r_[True, np.diff(torque_t) > 0.0]
        joint_torques = smooth_and_differentiate(resample(
            torque_t[keep_torque], torque[keep_torque], grid), dt, window_s)[0]
    else:
        joint_torques = np.zeros((grid.size, 0))
    depth = (resample(*series['/depth'], grid)[:, 0] if '/depth' in series
             else np.full(grid.size, np.nan))
    trim = round(window_s / dt)
    # A gap of any signal spoils the smoothing a window around it.
    gaps = {VELOCITY_TOPICS[velocity][1]: gap_mask(velocity_t, grid, MAX_VELOCITY_INTERVAL_S),
            REQUIRED['/imu']: gap_mask(imu_t, grid, MAX_SAMPLE_INTERVAL_S),
            REQUIRED['/joint_states']: gap_mask(joint_t, grid, MAX_SAMPLE_INTERVAL_S),
            REQUIRED['/command/actuators']: gap_mask(thrust_t, grid, MAX_SAMPLE_INTERVAL_S)}
    gap = np.logical_or.reduce(list(gaps.values()))
    valid = ~(np.convolve(gap.astype(float), np.ones(2 * trim + 1), mode='same') > 0.0)
    keep = slice(trim, grid.size - trim)
    gaps_s = {what: float(np.count_nonzero(mask[keep])) * dt for what, mask in gaps.items()
              if mask[keep].any()}
    result = Series(path, grid - grid[0], nu, nu_dot, euler_zyx(rotations),
                    rotations[:, 2, :], joints, joint_rates, joint_accelerations,
                    thrusts @ robot.thrust_matrix.T, thrusts, depth, valid,
                    joint_torques, gaps_s).window(
                        np.isin(np.arange(grid.size), np.arange(grid.size)[keep]))
    if float(np.abs(result.nu).max()) < MIN_SPEED:
        raise IdentifyError(f'{path}: no excitation: the vehicle never moved faster than '
                            f'{MIN_SPEED} m/s or rad/s on any axis (run the experiments of '
                            '`uvms identify plan`)')
    if float(result.thrusts.std(axis=0).max()) < MIN_THRUST_STD_N:
        raise IdentifyError(f'{path}: no excitation: no thrust varied by more than '
                            f'{MIN_THRUST_STD_N} N (standard deviation); run the experiments '
                            'of `uvms identify plan`')
    return result


def segments(series: Series, min_length_s: float = MIN_SEGMENT_S) -> list[Series]:
    """The contiguous stretches of ``series`` where the velocity is measured."""
    edges = np.flatnonzero(np.diff(np.r_[0, series.valid.astype(int), 0]))
    parts = []
    for begin, end in zip(edges[::2], edges[1::2], strict=True):
        if end - begin >= 3 and series.t_s[end - 1] - series.t_s[begin] >= min_length_s:
            mask = np.zeros(series.t_s.size, dtype=bool)
            mask[begin:end] = True
            parts.append(series.window(mask))
    return parts
