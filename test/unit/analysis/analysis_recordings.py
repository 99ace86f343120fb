"""Synthetic UVMS runs with known signals, written as ros2-profile MCAP recordings."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from uvms_recording.mcap_writer import McapRecorder, run_metadata
from uvms_recording.typestore import uvms_typestore

#: Sample period of every synthetic topic (s).
DT = 0.002
#: Simulated time of the first sample (s): t = 0 of the analysis.
T0 = 100.0
#: Log times are wall-clock-like and unrelated to the stamps (ns).
LOG_OFFSET_NS = 1_700_000_000 * 10**9

# The known contact run: contact from T_CONTACT to T_RELEASE_END; the force rises linearly to
# F_PEAK in RISE_S, decays as F_D + (F_PEAK - F_D) exp(-s / TAU) and is released linearly from
# T_RELEASE to T_RELEASE_END.
T_END = 6.0
T_CONTACT = 2.0
RISE_S = 0.1
F_D = 150.0
F_PEAK = 180.0
TAU = 0.2
T_RELEASE = 4.3
T_RELEASE_END = 4.5
#: Settling within 5 %: 30 exp(-s / TAU) = 7.5 at s = TAU ln 4, after the rise.
SETTLING_S = RISE_S + TAU * math.log(4.0)
WALL_X = 1.7771
N_THRUSTERS = 8

# Known position errors X_d - X (m): (startup t < 1 s, free motion, in contact) per axis.
ERROR_STARTUP = np.array([0.01, 0.004, -0.003])
ERROR_FREE = np.array([0.0004, 0.0005, 0.0003])
ERROR_CONTACT = np.array([0.02, 0.001, -0.002])

# Known vehicle motion: linear drift to DRIFT_END (m) and a yaw bump of YAW_MAX (rad).
DRIFT_END = np.array([0.003, 0.0, -0.004])
YAW_MAX = 0.02


@dataclass(frozen=True)
class Signals:
    """Time histories of one synthetic run, sampled at DT from t = 0.

    Attributes:
        t: Time (s), (n,).
        in_contact: Ground-truth contact flag, (n,).
        force_x: Normal contact force (N), (n,).
        f_d: Desired normal force (N), (n,).
        X_d: Desired end-effector position (m), (n, 3).
        X: End-effector position (m), (n, 3).
        W: Fuzzy weight, (n,).
        wall_x: Wall position (m), (n,).
        vehicle_position: Vehicle position (m), (n, 3).
        vehicle_yaw: Vehicle yaw (rad), (n,).
    """

    t: np.ndarray
    in_contact: np.ndarray
    force_x: np.ndarray
    f_d: np.ndarray
    X_d: np.ndarray
    X: np.ndarray
    W: np.ndarray
    wall_x: np.ndarray
    vehicle_position: np.ndarray
    vehicle_yaw: np.ndarray


def contact_force(t: np.ndarray) -> np.ndarray:
    """The known normal force profile of the contact run (N)."""
    s = t - T_CONTACT
    rise = F_PEAK * s / RISE_S
    decay = F_D + (F_PEAK - F_D) * np.exp(-(s - RISE_S) / TAU)
    f_release = F_D + (F_PEAK - F_D) * math.exp(-(T_RELEASE - T_CONTACT - RISE_S) / TAU)
    release = f_release * (T_RELEASE_END - t) / (T_RELEASE_END - T_RELEASE)
    force = np.where(s < RISE_S, rise, np.where(t < T_RELEASE, decay, release))
    return np.where((t >= T_CONTACT) & (t < T_RELEASE_END), force, 0.0)


def contact_signals(moving_wall: bool = False) -> Signals:
    """The contact run: half circle into the wall, known force, errors and vehicle motion."""
    t = np.round(np.arange(0.0, T_END + DT / 2, DT), 9)
    in_contact = (t >= T_CONTACT) & (t < T_RELEASE_END)
    return _signals(t, in_contact, contact_force(t), moving_wall)


def free_motion_signals() -> Signals:
    """The free-motion run: the same trajectory with no wall in reach."""
    t = np.round(np.arange(0.0, T_END + DT / 2, DT), 9)
    return _signals(t, np.zeros(t.size, bool), np.zeros(t.size), False)


def _signals(
    t: np.ndarray, in_contact: np.ndarray, force_x: np.ndarray, moving_wall: bool
) -> Signals:
    """Fill in trajectory, errors and vehicle motion around a contact profile."""
    angle = math.pi * t / T_END
    X_d = np.stack(
        [1.7 + 0.1 * np.sin(angle), np.zeros_like(t), 0.6 - 0.1 * np.cos(angle)], axis=1
    )
    error = np.where(
        in_contact[:, None], ERROR_CONTACT, np.where(t[:, None] < 1.0, ERROR_STARTUP, ERROR_FREE)
    )
    wall_x = np.full(t.size, WALL_X)
    if moving_wall:
        wall_x += 0.05 * np.clip(t - T_CONTACT - 0.5, 0.0, None)
    return Signals(
        t=t,
        in_contact=in_contact,
        force_x=force_x,
        f_d=np.full(t.size, F_D),
        X_d=X_d,
        X=X_d - error,
        W=np.where(in_contact, np.clip(1.0 - (t - T_CONTACT) / 0.3, 0.0, 1.0), 1.0),
        wall_x=wall_x,
        vehicle_position=np.array([0.5, 0.0, 1.0]) + np.outer(t / T_END, DRIFT_END),
        vehicle_yaw=YAW_MAX * np.sin(angle),
    )


TOPIC_TYPES = {
    '/uvms/contact': 'uvms_msgs/msg/ContactState',
    '/uvms/controller/state': 'uvms_msgs/msg/ControllerState',
    '/uvms/odometry': 'nav_msgs/msg/Odometry',
    '/uvms/ee_pose': 'geometry_msgs/msg/PoseStamped',
    '/uvms/thrusters/state': 'uvms_msgs/msg/ThrusterState',
}


def write_signals(
    path: Path, signals: Signals, scenario: str | None = None, thrusters: bool = True,
    mission: str = '',
) -> Path:
    """Write a synthetic run with the stack's recorder, as the graph would; returns the path.

    A mission (mission file text) goes into the metadata as the recorder stores a run's.
    """
    ts = uvms_typestore()
    T = ts.types
    Time, Header = T['builtin_interfaces/msg/Time'], T['std_msgs/msg/Header']
    Vector3, Point = T['geometry_msgs/msg/Vector3'], T['geometry_msgs/msg/Point']
    Quaternion = T['geometry_msgs/msg/Quaternion']
    Pose, Twist = T['geometry_msgs/msg/Pose'], T['geometry_msgs/msg/Twist']
    metadata = None if scenario is None else run_metadata(
        scenario, 0, '{}', **({'mission': mission} if mission else {}))
    recorder = McapRecorder(path, metadata=metadata)
    for topic, type_name in TOPIC_TYPES.items():
        if thrusters or topic != '/uvms/thrusters/state':
            recorder.add_topic(topic, type_name)

    def write(topic: str, msg: Any, log_time_ns: int) -> None:
        recorder.write(topic, bytes(ts.serialize_cdr(msg, msg.__msgtype__)), log_time_ns)

    zero = Vector3(x=0.0, y=0.0, z=0.0)
    for i, t in enumerate(signals.t):
        stamp_ns = round((T0 + t) * 1e9)
        log_ns = LOG_OFFSET_NS + stamp_ns + 37_000
        header = Header(
            stamp=Time(sec=stamp_ns // 10**9, nanosec=stamp_ns % 10**9), frame_id='map_ned'
        )
        force = Vector3(x=float(signals.force_x[i]), y=0.0, z=0.0)
        X, X_d = signals.X[i], signals.X_d[i]
        write(
            '/uvms/contact',
            T['uvms_msgs/msg/ContactState'](
                header=header,
                in_contact=bool(signals.in_contact[i]),
                force=force,
                penetration=float(signals.force_x[i]) / 1e4,
                wall_position=float(signals.wall_x[i]),
                wall_velocity=0.0,
            ),
            log_ns,
        )
        write(
            '/uvms/controller/state',
            T['uvms_msgs/msg/ControllerState'](
                header=header,
                weight=float(signals.W[i]),
                phase=2 if signals.in_contact[i] else 0,
                contact_force=force,
                desired_force=Vector3(x=float(signals.f_d[i]), y=0.0, z=0.0),
                position=Point(x=float(X[0]), y=float(X[1]), z=float(X[2])),
                desired_position=Point(x=float(X_d[0]), y=float(X_d[1]), z=float(X_d[2])),
                velocity=zero,
                desired_velocity=zero,
                normal_velocity=0.0,
                impedance_force=zero,
                hybrid_force=zero,
                command_force=zero,
            ),
            log_ns + 1000,
        )
        p = signals.vehicle_position[i]
        yaw = float(signals.vehicle_yaw[i])
        orientation = Quaternion(x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))
        write(
            '/uvms/odometry',
            T['nav_msgs/msg/Odometry'](
                header=header,
                child_frame_id='base_link_frd',
                pose=T['geometry_msgs/msg/PoseWithCovariance'](
                    pose=Pose(
                        position=Point(x=float(p[0]), y=float(p[1]), z=float(p[2])),
                        orientation=orientation,
                    ),
                    covariance=np.zeros(36),
                ),
                twist=T['geometry_msgs/msg/TwistWithCovariance'](
                    twist=Twist(linear=zero, angular=zero), covariance=np.zeros(36)
                ),
            ),
            log_ns + 2000,
        )
        write(
            '/uvms/ee_pose',
            T['geometry_msgs/msg/PoseStamped'](
                header=header,
                pose=Pose(
                    position=Point(x=float(X[0]), y=float(X[1]), z=float(X[2])),
                    orientation=Quaternion(x=0.0, y=0.0, z=0.0, w=1.0),
                ),
            ),
            log_ns + 3000,
        )
        if thrusters:
            thrust = 10.0 * np.sin(t + np.arange(N_THRUSTERS))
            write(
                '/uvms/thrusters/state',
                T['uvms_msgs/msg/ThrusterState'](
                    header=header,
                    desired_thrust=thrust,
                    actual_thrust=0.9 * thrust,
                    propeller_speed=np.sign(thrust) * np.sqrt(np.abs(thrust)) * 10.0,
                    reference_speed=np.sign(thrust) * np.sqrt(np.abs(thrust)) * 10.0,
                    motor_current=np.abs(thrust) * 0.1,
                    achieved_wrench=T['geometry_msgs/msg/Wrench'](force=zero, torque=zero),
                    saturation_scale=1.0,
                ),
                log_ns + 4000,
            )
    recorder.close()
    return path
