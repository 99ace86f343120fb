"""Recordings of a simulated vehicle with known hull terms, as the robot would record them.

The robot folder's own model (uvms_model, the simulator's) is stepped with a known hull and
known thrusts, the arm held by a joint PD; IMU (orientation, rates), DVL (velocity at its
mounting point in dvl_link), depth, joint states and the thrusts sent are written to an MCAP
with the stack's recorder, noise free. ``topics`` leaves any out; ``holes_s`` leaves a topic's
messages out over stretches of time, as a recorder that fell behind does.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from uvms_identify.known_terms import model_with_hull, start_joints
from uvms_identify.robot_data import RobotData
from uvms_identify.signals import rpy_matrix
from uvms_recording.mcap_writer import McapRecorder
from uvms_recording.typestore import uvms_typestore

TOPICS = {
    '/uvms/imu': 'sensor_msgs/msg/Imu',
    '/uvms/dvl': 'geometry_msgs/msg/TwistWithCovarianceStamped',
    '/uvms/depth': 'geometry_msgs/msg/PoseWithCovarianceStamped',
    '/uvms/joint_states': 'sensor_msgs/msg/JointState',
    '/uvms/command/actuators': 'uvms_msgs/msg/ActuatorCommand',
}
DT = 0.002
DVL_EVERY = 50  # 10 Hz
WRITE_EVERY = 5  # IMU, joint states and thrusts at 100 Hz


def excitation(robot: RobotData, duration_s: float, seed: int = 0,
               axes: tuple[int, ...] = (0, 1, 2, 3, 4, 5)) -> tuple[np.ndarray, np.ndarray]:
    """Times (N,) and thrusts (N, p): per axis a sum of sines about a static offset."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration_s, DT)
    wrench = np.zeros((t.size, 6))
    peak = np.array([40.0, 40.0, 50.0, 0.4, 0.5, 1.2])
    for axis in axes:
        offset = peak[axis] * 0.4 * np.sign(np.sin(2 * np.pi * t / rng.uniform(6.0, 9.0)))
        wave = sum(np.sin(2 * np.pi * rng.uniform(0.05, 0.8) * t + rng.uniform(0, 6))
                   for _ in range(3))
        wrench[:, axis] = offset + 0.25 * peak[axis] * wave
    return t, wrench @ np.linalg.pinv(robot.thrust_matrix).T


def simulate(robot: RobotData, hull: dict[str, Any], t: np.ndarray,
             thrusts: np.ndarray) -> dict[str, np.ndarray]:
    """States (q, w) per sample of the robot with ``hull`` under ``thrusts``."""
    model = model_with_hull(robot, hull)
    q = np.zeros(model.n_dof)
    q[2] = 2.0
    q0 = start_joints(robot, model.n_joints)
    q[6:] = q0
    w = np.zeros(model.n_dof)
    qs, ws = np.empty((t.size, model.n_dof)), np.empty((t.size, model.n_dof))
    for k in range(t.size):
        qs[k], ws[k] = q, w
        tau = np.zeros(model.n_dof)
        tau[:6] = robot.thrust_matrix @ thrusts[k]
        tau[6:] = -2.0 * (q[6:] - q0) - 0.1 * w[6:]
        q, w = model.step(q, w, tau, None, DT)
    return {'q': qs, 'w': ws}


def write(path: Path, robot: RobotData, t: np.ndarray, thrusts: np.ndarray,
          states: dict[str, np.ndarray], topics: tuple[str, ...] = tuple(TOPICS),
          holes_s: dict[str, list[tuple[float, float]]] | None = None) -> Path:
    """Write the robot's own topics of a simulated run to ``path``.

    ``holes_s``: per topic, the (start, end) times (s) whose messages are left out.
    """
    holes = holes_s or {}
    ts = uvms_typestore()
    T = ts.types
    Time, Header = T['builtin_interfaces/msg/Time'], T['std_msgs/msg/Header']
    Vector3, Quaternion = T['geometry_msgs/msg/Vector3'], T['geometry_msgs/msg/Quaternion']
    recorder = McapRecorder(path)
    for topic in topics:
        recorder.add_topic(topic, TOPICS[topic])

    def put(topic: str, msg: Any, stamp_ns: int) -> None:
        if any(start <= stamp_ns * 1e-9 < end for start, end in holes.get(topic, ())):
            return
        if topic in topics:
            recorder.write(topic, bytes(ts.serialize_cdr(msg, msg.__msgtype__)), stamp_ns)

    covariance9 = np.zeros(9)
    covariance36 = np.zeros(36)
    names = [f'joint_{i + 1}' for i in range(states['q'].shape[1] - 6)]
    for k, time_s in enumerate(t):
        stamp_ns = round(time_s * 1e9)
        header = Header(stamp=Time(sec=stamp_ns // 10**9, nanosec=stamp_ns % 10**9),
                        frame_id='base_link_frd')
        q, w = states['q'][k], states['w'][k]
        rotation = rpy_matrix(*q[3:6])
        quaternion = _quaternion(rotation)
        if k % WRITE_EVERY == 0:
            put('/uvms/imu', T['sensor_msgs/msg/Imu'](
                header=header, orientation=Quaternion(x=quaternion[0], y=quaternion[1],
                                                      z=quaternion[2], w=quaternion[3]),
                orientation_covariance=covariance9,
                angular_velocity=Vector3(x=w[3], y=w[4], z=w[5]),
                angular_velocity_covariance=covariance9,
                linear_acceleration=Vector3(x=0.0, y=0.0, z=-9.81),
                linear_acceleration_covariance=covariance9), stamp_ns)
            put('/uvms/joint_states', T['sensor_msgs/msg/JointState'](
                header=header, name=names, position=q[6:].copy(), velocity=w[6:].copy(),
                effort=np.zeros(len(names))), stamp_ns)
            put('/uvms/command/actuators', T['uvms_msgs/msg/ActuatorCommand'](
                header=header, thrust=thrusts[k].copy(), joint_names=names,
                joint_torques=np.zeros(len(names))), stamp_ns)
        if k % DVL_EVERY == 0:
            v = robot.dvl_rotation.T @ (w[:3] + np.cross(w[3:6], robot.dvl_position_m))
            twist = T['geometry_msgs/msg/Twist'](linear=Vector3(x=v[0], y=v[1], z=v[2]),
                                                  angular=Vector3(x=0.0, y=0.0, z=0.0))
            put('/uvms/dvl', T['geometry_msgs/msg/TwistWithCovarianceStamped'](
                header=header, twist=T['geometry_msgs/msg/TwistWithCovariance'](
                    twist=twist, covariance=covariance36)), stamp_ns)
            pose = T['geometry_msgs/msg/Pose'](
                position=T['geometry_msgs/msg/Point'](x=0.0, y=0.0, z=q[2]),
                orientation=Quaternion(x=0.0, y=0.0, z=0.0, w=1.0))
            put('/uvms/depth', T['geometry_msgs/msg/PoseWithCovarianceStamped'](
                header=header, pose=T['geometry_msgs/msg/PoseWithCovariance'](
                    pose=pose, covariance=covariance36)), stamp_ns)
    recorder.close()
    return path


def _quaternion(rotation: np.ndarray) -> np.ndarray:
    """x, y, z, w of a rotation matrix (w > 0 branch; the vehicle stays near level)."""
    w = 0.5 * np.sqrt(max(1.0 + np.trace(rotation), 1e-12))
    return np.array([(rotation[2, 1] - rotation[1, 2]) / (4 * w),
                     (rotation[0, 2] - rotation[2, 0]) / (4 * w),
                     (rotation[1, 0] - rotation[0, 1]) / (4 * w), w])
