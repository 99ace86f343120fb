"""The simulated robot: UVMS dynamics, the wall it touches and the wrist sensor that feels it.

Pure numpy and uvms_model. One fixed step integrates (q, w) of eq. 8 with the generalized
body forces tau_b = E [thrusts; joint torques] (eq. 9) and the contact: the end effector
exerts F_e on the wall, so the wall pushes back on it with -F_e (paper sec. 5.1). Simulated
time is kept in integer nanoseconds, so stamps are exact and runs repeat bit for bit.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any, NoReturn

import numpy as np
from numpy.typing import ArrayLike, NDArray
from uvms_model.contact import ContactState, WallContact
from uvms_model.ocean_current import CurrentParameters, OceanCurrent
from uvms_model.sensors import ForceTorqueSensor, contact_wrench_in_sensor_frame
from uvms_model.thrusters import configuration_matrix

from uvms_model import (
    ModelError,
    SingularAttitudeError,
    UnreachableError,
    UvmsModel,
    UvmsParameters,
)
from uvms_sim.errors import CommandError, DivergenceError, SimParameterError, SimulationError

FloatArray = NDArray[np.float64]

_NO_CONTACT = ContactState(False, np.zeros(3), 0.0, math.nan, 0.0)
_SENSOR_FRAMES = ('ee_link', 'ft_sensor_link')


@dataclass(frozen=True)
class DivergenceLimits:
    """Bounds beyond which the state is taken as diverged and the simulation stops.

    They sit far above anything a 530 kg vehicle with a 1.5 m arm reaches under its
    thrusters, and far below where a numerical blow-up ends, so a blow-up is caught early.

    Attributes:
        max_distance_m: Vehicle distance from the map_ned origin (m).
        max_linear_speed_m_s: Vehicle speed |[u, v, w]| (m/s).
        max_angular_rate_rad_s: Vehicle body rate |[p, q, r]| (rad/s).
        max_joint_rate_rad_s: Each arm joint rate (rad/s).
    """

    max_distance_m: float = 1.0e4
    max_linear_speed_m_s: float = 20.0
    max_angular_rate_rad_s: float = 20.0
    max_joint_rate_rad_s: float = 50.0


@dataclass(frozen=True)
class Observation:
    """What the plant shows at one instant: state, frames, contact truth and sensor reading.

    Attributes:
        t_ns: Simulated time (ns).
        q: Generalized coordinates (6 + n,).
        w: Quasi-velocities (6 + n,).
        joint_torques: Motor torques applied during the last step (N*m).
        poses: {frame: (p_ned, rot_ned_from_frame)} of the robot's frames (only ee_link and
            ft_sensor_link from ``Plant.observe(all_frames=False)``).
        contact: Contact ground truth (force on the wall in map_ned).
        sensor_force: Wrist sensor force reading in ft_sensor_link (N).
        sensor_torque: Wrist sensor torque reading in ft_sensor_link (N*m).
    """

    t_ns: int
    q: FloatArray
    w: FloatArray
    joint_torques: FloatArray
    poses: dict[str, tuple[FloatArray, FloatArray]]
    contact: ContactState
    sensor_force: FloatArray
    sensor_torque: FloatArray


def initial_coordinates(
    model: UvmsModel,
    vehicle_pose: ArrayLike,
    joint_positions: ArrayLike,
    ee_position: ArrayLike | None = None,
    robot: str = '',
    robot_start: Mapping[str, Any] | None = None,
) -> FloatArray:
    """Generalized coordinates q (6 + n,) of the start, optionally by inverse kinematics.

    Args:
        model: The UVMS model.
        vehicle_pose: x, y, z (m) in map_ned and roll, pitch, yaw (rad), shape (6,).
        joint_positions: Arm joint angles (rad) (n,); with ``ee_position``, the starting guess
            of the inverse kinematics (it selects the elbow branch).
        ee_position: End-effector position in map_ned (m) (3,) to start at, or None.
        robot: The robot's name, for the error message.
        robot_start: The robot's default start (``initial.*`` of its ``start.yaml``), named
            in the error message as what fits the robot.

    Raises:
        SimParameterError: The end-effector position is out of reach (naming the robot, the
            residual and the robot's default start), or the joint angles do not fit the arm.
    """
    pose = np.asarray(vehicle_pose, dtype=float)
    arm = np.asarray(joint_positions, dtype=float)
    whose = f'robot {robot!r}: ' if robot else ''
    if arm.shape != (model.n_joints,):
        msg = (f"{whose}parameter 'initial.joint_positions' = {arm.tolist()}: expected "
               f'{model.n_joints} angles, one per arm joint {list(model.joint_names)}')
        raise SimParameterError(msg + _default_start_hint(robot_start))
    if ee_position is not None:
        try:
            arm = model.joint_positions_for_ee_position(pose, ee_position, arm)
        except UnreachableError as exc:
            msg = (
                f"{whose}parameter 'initial.ee_position' = "
                f'{np.asarray(ee_position, float).tolist()}: out of reach of the arm from '
                f'initial.vehicle_pose = {pose.tolist()} (residual {exc.residual_m:.3g} m)'
            )
            raise SimParameterError(msg + _default_start_hint(robot_start)) from exc
    return np.concatenate((pose, arm))


def _default_start_hint(robot_start: Mapping[str, Any] | None) -> str:
    """'; the robot's default start: initial.x = v, ...' for an error message, or ''."""
    if not robot_start:
        return ''
    values = ', '.join(f'{name} = {value}' for name, value in robot_start.items())
    return (f"; the robot's default start (its start.yaml, taken where initial.* is not set): "
            f'{values}')


class Plant:
    """UVMS plant with wall contact, wrist force/torque sensor and actuator mapping.

    Args:
        params: Robot parameters (model, ``contact.*``, ``sensor.*``, ``thrusters.*``,
            ``integration.method``).
        q0: Initial generalized coordinates (6 + n,).
        dt_ns: Fixed integration step (ns).
        wall_enabled: Whether the wall exists.
        wall_motion_start_force_n: Contact force (N) at which a moving wall
            (``contact.wall_speed_m_s``) starts to move; 0 starts it at the first touch, as
            ``uvms_model.contact`` does.
        limits: Divergence bounds.
        current: The ocean current's process (``uvms_model.ocean_current``), seeded with
            ``sensor.seed`` (the scenario's seed); None or all zero: still water.

    Example:
        >>> plant = Plant(UvmsParameters(), np.zeros(9))  # paper robot; doctest: +SKIP
        >>> plant.step(np.zeros(plant.n_thrusters), np.zeros(3))  # doctest: +SKIP
        >>> plant.t_ns  # doctest: +SKIP
        1000000
    """

    def __init__(
        self,
        params: UvmsParameters,
        q0: ArrayLike,
        dt_ns: int = 1_000_000,
        wall_enabled: bool = True,
        wall_motion_start_force_n: float = 0.0,
        limits: DivergenceLimits | None = None,
        current: CurrentParameters | None = None,
    ) -> None:
        if dt_ns <= 0:
            msg = f'dt_ns must be a positive number of nanoseconds, got {dt_ns}'
            raise SimParameterError(msg)
        self.model = UvmsModel(params)
        self.joint_names: tuple[str, ...] = self.model.joint_names
        self.n_joints = self.model.n_joints
        self._e = configuration_matrix(params.thrusters, self.n_joints)
        self.n_thrusters = self._e.shape[1] - self.n_joints
        self._contact_params = params.contact
        self._motion_start_force_n = wall_motion_start_force_n
        self._wall_waits = wall_motion_start_force_n > 0.0 and params.contact.wall_speed_m_s != 0.0
        # A wall that waits for a force holds still until then; a fresh moving wall then
        # takes over at the same place and, touched at once, starts moving (Case III).
        still = replace(params.contact, wall_speed_m_s=0.0) if self._wall_waits else None
        self._wall = WallContact(still or params.contact) if wall_enabled else None
        self._damped_wall = params.contact.damping_n_s_m > 0.0
        self._sensor = ForceTorqueSensor(params.sensor)
        self._limits = limits if limits is not None else DivergenceLimits()
        self._dt_ns = int(dt_ns)
        self._dt_s = dt_ns * 1e-9
        self._t_ns = 0
        self._last_reading_ns: int | None = None
        self._q = np.array(q0, dtype=float)
        self._w = np.zeros(self.model.n_dof)
        self._thrusts = np.zeros(self.n_thrusters)
        self._joint_torques = np.zeros(self.n_joints)
        self._failure: SimulationError | None = None
        self._current = OceanCurrent(current, params.sensor.seed)
        self._check_state(None)

    @property
    def t_ns(self) -> int:
        """Simulated time (ns)."""
        return self._t_ns

    @property
    def dt_ns(self) -> int:
        """Fixed integration step (ns)."""
        return self._dt_ns

    @property
    def q(self) -> FloatArray:
        """Generalized coordinates (6 + n,): vehicle position and Euler angles, joint angles."""
        return self._q.copy()

    @property
    def w(self) -> FloatArray:
        """Quasi-velocities (6 + n,): body linear and angular velocity, joint rates."""
        return self._w.copy()

    @property
    def current_ned(self) -> FloatArray:
        """The water's velocity (m/s, map_ned) the next step applies (zero in still water)."""
        return self._current.velocity_ned

    @property
    def current_parameters(self) -> CurrentParameters:
        """The ocean current's parameters in force."""
        return self._current.params

    def set_current(self, params: CurrentParameters) -> None:
        """Replace the current's parameters (at run time too); it restarts at their means."""
        self._current.configure(params)

    @property
    def joint_torques(self) -> FloatArray:
        """Arm motor torques applied during the last step (N*m)."""
        return self._joint_torques.copy()

    @property
    def thrusts(self) -> FloatArray:
        """Thrusts applied during the last step (N)."""
        return self._thrusts.copy()

    def tau_body(self, thrusts: ArrayLike, joint_torques: ArrayLike) -> FloatArray:
        """Generalized body forces tau_b = E [thrusts; joint torques] (eq. 9)."""
        result: FloatArray = self._e @ np.concatenate(
            (np.asarray(thrusts, dtype=float), np.asarray(joint_torques, dtype=float))
        )
        return result

    def contact(self) -> ContactState:
        """Contact ground truth at the current state (no contact without a wall)."""
        return self._contact_at(self.model.ee_position(self._q))

    def read_wrench_sensor(self) -> tuple[FloatArray, FloatArray]:
        """One reading of the wrist sensor: (force N, torque N*m) in ft_sensor_link.

        The sensor feels F_e, the force the end effector exerts on the wall, with noise,
        saturation and the optional low-pass of ``sensor.*``. Each call draws new noise.
        """
        observation = self.observe()
        return observation.sensor_force, observation.sensor_torque

    def frame_poses(self) -> dict[str, tuple[FloatArray, FloatArray]]:
        """Poses of the robot's frames in map_ned: {frame: (p_ned, rot_ned_from_frame)}."""
        return self.model.frame_poses(self._q)

    def observe(self, all_frames: bool = True) -> Observation:
        """State, frames, contact and one wrist sensor reading (draws new sensor noise).

        The kinematics are evaluated once for all of them.

        Args:
            all_frames: Pose every robot frame; False poses only ee_link and
                ft_sensor_link, all the sensor topics need (no /tf at this state).
        """
        poses = self.model.frame_poses(self._q, None if all_frames else _SENSOR_FRAMES)
        contact = self._contact_at(poses['ee_link'][0])
        force, torque = contact_wrench_in_sensor_frame(poses['ft_sensor_link'][1],
                                                       contact.force_ned)
        dt = self._dt_s
        if self._last_reading_ns is not None and self._t_ns > self._last_reading_ns:
            dt = (self._t_ns - self._last_reading_ns) * 1e-9
        self._last_reading_ns = self._t_ns
        force, torque = self._sensor.measure(force, torque, dt)
        return Observation(self._t_ns, self._q.copy(), self._w.copy(),
                           self._joint_torques.copy(), poses, contact, force, torque)

    def _contact_at(self, p_ee_ned: FloatArray) -> ContactState:
        """Contact ground truth for the end effector at p_ee_ned, at the current time."""
        if self._wall is None:
            return _NO_CONTACT
        return self._wall.evaluate(self._t_ns * 1e-9, p_ee_ned, self._ee_velocity())

    def step(self, thrusts: ArrayLike, joint_torques: ArrayLike) -> None:
        """Advance the plant by one fixed step with the given actuator outputs held.

        Args:
            thrusts: Thrust of each thruster (N), shape (p,).
            joint_torques: Arm motor torques (N*m), shape (n,).

        Raises:
            CommandError: Wrong size or non-finite actuator outputs; nothing is integrated.
            DivergenceError: The step would leave a finite, bounded state; the state stays
                at the last valid one and every later step raises too.
            SimulationError: The plant already stopped after a divergence.
        """
        if self._failure is not None:
            msg = f'the simulation stopped at t = {self._t_ns * 1e-9:.3f} s: {self._failure}'
            raise SimulationError(msg)
        thrusts = _actuator_vector('thrusts', thrusts, self.n_thrusters, 'N')
        joint_torques = _actuator_vector('joint_torques', joint_torques, self.n_joints, 'N*m')
        tau_b = self.tau_body(thrusts, joint_torques)
        t_s = self._t_ns * 1e-9
        f_on_ee = None
        if self._wall is not None:
            p_ee = self.model.ee_position(self._q)
            contact = self._wall.update(t_s, p_ee, self._ee_velocity())
            if self._wall_waits and contact.force_ned[0] >= self._motion_start_force_n:
                self._wall_waits = False
                self._wall = WallContact(replace(
                    self._contact_params, wall_position_m=contact.wall_position_m))
                contact = self._wall.update(t_s, p_ee, self._ee_velocity())
            if contact.in_contact:
                f_on_ee = -contact.force_ned
        # Still water takes the model's path without a current (bit-identical to no current).
        current = self._current.velocity_ned if self._current.enabled else None
        try:
            q, w = self.model.step(self._q, self._w, tau_b, f_on_ee, self._dt_s,
                                   current_ned=current)
        except SingularAttitudeError as exc:
            self._fail(DivergenceError(
                f'the vehicle pitch reached the Euler-angle singularity (+-90 deg) at '
                f't = {t_s:.3f} s: {exc}'
            ))
        except ModelError as exc:
            self._fail(DivergenceError(
                f'the state became non-finite in the step from t = {t_s:.3f} s: {exc}'
            ))
        previous = (self._q, self._w)
        self._q, self._w = q, w
        try:
            self._check_state(t_s)
        except DivergenceError as exc:
            self._q, self._w = previous
            self._fail(exc)
        self._thrusts = thrusts
        self._joint_torques = joint_torques
        self._current.step(self._dt_s)
        self._t_ns += self._dt_ns

    def _fail(self, error: SimulationError) -> NoReturn:
        """Remember the failure and raise it."""
        self._failure = error
        raise error

    def _ee_velocity(self) -> FloatArray | None:
        """End-effector velocity in map_ned (m/s), only when the wall damping needs it."""
        if not self._damped_wall:
            return None
        q_dot = self.model.velocity_transform(self._q) @ self._w
        result: FloatArray = self.model.ee_jacobian(self._q) @ q_dot
        return result

    def _check_state(self, t_s: float | None) -> None:
        """Raise DivergenceError if the state is non-finite or out of its bounds.

        Args:
            t_s: Start time (s) of the step that led to the state; None for the initial state.
        """
        q, w, lim = self._q, self._w, self._limits
        q_list, w_list = q.tolist(), w.tolist()
        # A finite sum is the cheap test (a huge finite sum may overflow: then look again).
        finite = math.isfinite(sum(q_list) + sum(w_list))
        if not finite and not (np.isfinite(q).all() and np.isfinite(w).all()):
            names = ('x', 'y', 'z', 'roll', 'pitch', 'yaw', *self.joint_names)
            label, vector = ('q', q) if not np.isfinite(q).all() else ('w', w)
            i = int(np.flatnonzero(~np.isfinite(vector))[0])
            msg = f'{_where(t_s)}: {label}[{i}] ({names[i]}) = {vector[i]} is not finite'
            raise DivergenceError(msg)
        x, y, z = q_list[:3]
        u, v, w_, p, q_, r = w_list[:6]
        joint_rate = max(abs(rate) for rate in w_list[6:])
        checks = (
            ('vehicle distance from the map_ned origin', math.sqrt(x * x + y * y + z * z),
             lim.max_distance_m, 'm'),
            ('vehicle speed |[u, v, w]|', math.sqrt(u * u + v * v + w_ * w_),
             lim.max_linear_speed_m_s, 'm/s'),
            ('vehicle angular rate |[p, q, r]|', math.sqrt(p * p + q_ * q_ + r * r),
             lim.max_angular_rate_rad_s, 'rad/s'),
            ('largest arm joint rate', joint_rate,
             lim.max_joint_rate_rad_s, 'rad/s'),
        )
        for label, value, limit, unit in checks:
            if value > limit:
                msg = (
                    f'{_where(t_s)}: the state diverged: {label} = {value:.4g} {unit} exceeds '
                    f'{limit:g} {unit}'
                )
                raise DivergenceError(msg)


def _where(t_s: float | None) -> str:
    """Name the state of a check: the initial one, or the one after the step from t_s."""
    return 'initial state' if t_s is None else f'the step from t = {t_s:.3f} s'


def _actuator_vector(name: str, value: ArrayLike, size: int, unit: str) -> FloatArray:
    """Check size and finiteness of an actuator output vector."""
    array = np.asarray(value, dtype=float)
    if array.shape != (size,):
        msg = f'{name} must have {size} values ({unit}), got shape {array.shape}'
        raise CommandError(msg)
    if not math.isfinite(sum(array.tolist())) and not np.isfinite(array).all():
        msg = f'{name} must be finite ({unit}), got {array.tolist()}'
        raise CommandError(msg)
    return array
