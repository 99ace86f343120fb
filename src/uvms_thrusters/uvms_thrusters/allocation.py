"""Thruster and motor allocation (paper eq. 9-10) with direction-preserving saturation.

tau_b = E F_td (eq. 9) with E = [[T, 0], [0, I_n]]: T (6, p) maps thrusts to the vehicle
wrench in base_link_frd, and each arm motor drives its own joint. The desired thrusts and
motor torques are F_td = E⁺ tau_b (eq. 10), E⁺ = Eᵀ (E Eᵀ)⁻¹ computed once.

Saturation: clipping each thruster on its own would turn the wrench that the thrusters
produce away from the commanded one (a surge command would grow a yaw moment). Instead the
whole vehicle wrench is scaled by the largest factor s in (0, 1] that keeps every thruster
within its limit, so the achieved wrench s tau_v is parallel to the commanded one. Arm
torques are scaled likewise, by their own factor, against the motor torque limits.

Thrust limits are the magnitudes ``thrusters.max_thrust_n`` of the robot, in both directions:
reverse thrust is weaker per revolution (thruster_dynamics), so the propeller turns faster in
reverse for the same thrust, and the start-up check makes sure the motor current limit can
hold each limit in both directions.

Accommodation of thruster faults: with an estimated effectiveness η̂ (p,) in [0, 1] per
thruster (``uvms_thrusters.fault_detection``), the allocation runs on T diag(η̂) by its
pseudo-inverse u = (T diag(η̂))⁺ tau_v = diag(η̂) Tᵀ (T diag(η̂²) Tᵀ)⁻¹ tau_v, the weighted
minimum-norm solution: a thruster at η̂ = 0 has its column out and is commanded zero, a weak
one is used less. The rank of T diag(η̂) is checked: below 6 the vehicle is no longer fully
actuated, the allocation is the least-squares one (the wrench's reachable part) and
``ThrusterAllocator.fully_actuated`` is False. η̂ = 1 everywhere gives T⁺, as above.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
from uvms_model.jit import kernel

from uvms_thrusters.errors import ThrusterInputError, ThrusterParameterError
from uvms_thrusters.fault_detection import ThrusterFaultDetector
from uvms_thrusters.thruster_dynamics import ThrusterBank, ThrusterModelParameters
from uvms_thrusters.thruster_faults import (
    EscFeedback,
    EscSensor,
    ThrusterFaultInjector,
    reference_speed,
)

FloatArray = npt.NDArray[np.float64]


@kernel
def _scale_into_limits(values: FloatArray, inv_limit: FloatArray) -> float:
    """Scale ``values`` in place by the largest s in (0, 1] that keeps each |v_i| s <= limit_i.

    Returns:
        s (1.0 when every value is within its limit).
    """
    worst = 0.0
    for i in range(values.size):
        worst = max(worst, abs(values[i]) * inv_limit[i])
    if worst <= 1.0:
        return 1.0
    scale = 1.0 / worst
    for i in range(values.size):
        values[i] *= scale
    return scale


@kernel
def saturate_allocation(
    tau: FloatArray,
    thrust: FloatArray,
    inv_limit: FloatArray,
    joints: FloatArray,
    inv_joint: FloatArray,
) -> tuple[bool, float, float]:
    """Scale thrusts F_td = T⁺ tau_v and motor torques tau_q into their limits, in place.

    ``thrust`` holds T⁺ tau_v on entry (eq. 10; E⁺ = blockdiag(T⁺, I_n) since E is block
    diagonal); the motor torques tau_b[6:] are copied into ``joints``. Each part is scaled
    by its own factor (see the module docstring).

    Returns:
        (False, 1, 1) with nothing scaled if tau holds a NaN or Inf; else (True, thrust
        scale, joint scale).
    """
    for i in range(tau.size):
        if not np.isfinite(tau[i]):
            return False, 1.0, 1.0
    scale = _scale_into_limits(thrust, inv_limit)
    for i in range(joints.size):
        joints[i] = tau[6 + i]
    return True, scale, _scale_into_limits(joints, inv_joint)


#: Relative singular-value tolerance under which T diag(η̂) counts as rank deficient.
RANK_TOLERANCE = 1e-9


def weighted_pseudo_inverse(
    thrust_matrix: FloatArray, effectiveness: FloatArray
) -> tuple[FloatArray, int]:
    """(T diag(η̂))⁺ (p, 6) and the rank of T diag(η̂) (see the module docstring).

    Args:
        thrust_matrix: T (6, p).
        effectiveness: η̂ (p,), each in [0, 1].

    Returns:
        The pseudo-inverse and the rank (singular values above ``RANK_TOLERANCE`` times
        the largest).

    Example:
        >>> t = np.hstack([np.eye(6), np.eye(6)[:, :1]])  # a 7th thruster doubling surge
        >>> pinv, rank = weighted_pseudo_inverse(t, np.array([0.0, 1, 1, 1, 1, 1, 1]))
        >>> rank, (pinv @ np.eye(6)[0]).round(12).tolist()
        (6, [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0])
    """
    t_eff = thrust_matrix * np.asarray(effectiveness, dtype=np.float64)[np.newaxis, :]
    sigma = np.linalg.svd(t_eff, compute_uv=False)
    rank = int(np.count_nonzero(sigma > RANK_TOLERANCE * max(float(sigma[0]), 1e-300)))
    if rank == t_eff.shape[0]:
        return t_eff.T @ np.linalg.inv(t_eff @ t_eff.T), rank
    return np.asarray(np.linalg.pinv(t_eff, rcond=RANK_TOLERANCE), dtype=np.float64), rank


@dataclass(frozen=True)
class AllocatorParameters:
    """Everything the allocator needs.

    Attributes:
        thrust_matrix: T (6, p), column i = [d_i; r_i x d_i] in base_link_frd, from
            ``uvms_model.thrusters.ThrusterLayout.thrust_matrix()``.
        max_thrust: thrust magnitude limit of each thruster (p,) (N), forward and reverse,
            ``thrusters.max_thrust_n``.
        max_joint_torque: torque limit of each arm motor (n,) (N m).
        thruster: constants of the thruster model (eq. 11-15).
    """

    thrust_matrix: FloatArray
    max_thrust: FloatArray
    max_joint_torque: FloatArray
    thruster: ThrusterModelParameters = field(default_factory=ThrusterModelParameters)

    def __post_init__(self) -> None:
        t = np.asarray(self.thrust_matrix, dtype=np.float64)
        if t.ndim != 2 or t.shape[0] != 6 or t.shape[1] < 6 or not np.all(np.isfinite(t)):
            raise ThrusterParameterError(
                'thrusters.positions_m/directions',
                t.shape,
                'a finite thrust matrix T of shape (6, p >= 6)',
            )
        if np.linalg.matrix_rank(t) < 6:
            raise ThrusterParameterError(
                'thrusters.positions_m/directions',
                'rank < 6',
                'a thrust matrix of full row rank 6',
            )
        limits = np.asarray(self.max_thrust, dtype=np.float64)
        if (
            limits.shape != (t.shape[1],)
            or not np.all(np.isfinite(limits))
            or np.any(limits <= 0.0)
        ):
            raise ThrusterParameterError(
                'thrusters.max_thrust_n', limits.tolist(), f'{t.shape[1]} values in (0, inf) N'
            )
        torques = np.asarray(self.max_joint_torque, dtype=np.float64)
        if (
            torques.ndim != 1
            or torques.size < 1
            or not np.all(np.isfinite(torques))
            or np.any(torques <= 0.0)
        ):
            raise ThrusterParameterError(
                'allocator.max_joint_torque_n_m',
                torques.tolist(),
                'one value in (0, inf) N m per joint',
            )
        object.__setattr__(self, 'thrust_matrix', t)
        object.__setattr__(self, 'max_thrust', limits)
        object.__setattr__(self, 'max_joint_torque', torques)

    @property
    def n_thrusters(self) -> int:
        """Number of thrusters p."""
        return int(self.thrust_matrix.shape[1])

    @property
    def n_joints(self) -> int:
        """Number of arm motors n."""
        return int(self.max_joint_torque.size)

    def configuration_matrix(self) -> FloatArray:
        """E (6 + n, p + n) of eq. 9."""
        p, n = self.n_thrusters, self.n_joints
        e = np.zeros((6 + n, p + n))
        e[:6, :p] = self.thrust_matrix
        e[6:, p:] = np.eye(n)
        return e


@dataclass
class AllocationResult:
    """Static allocation of one generalized force (eq. 10 after saturation).

    Attributes:
        thrust: desired thrusts F_td,v (p,) within the limits (N).
        joint_torques: motor torques F_td,m (n,) within the limits (N m).
        achieved_wrench: T diag(η̂) F_td,v (6,), the vehicle wrench the desired thrusts
            produce at the estimated effectiveness η̂ (T F_td,v while every η̂ is 1).
        saturation_scale: s in (0, 1] applied to the vehicle wrench; 1 when unsaturated.
        joint_scale: factor in (0, 1] applied to the joint torques.
    """

    thrust: FloatArray
    joint_torques: FloatArray
    achieved_wrench: FloatArray
    saturation_scale: float
    joint_scale: float


@dataclass
class AllocatorOutput:
    """One allocator step: the static allocation plus the thruster dynamics (eq. 11-15).

    The arrays are the allocator's own buffers, overwritten by the next step.

    Attributes:
        allocation: the static allocation (desired thrusts after saturation).
        thrust: actual thrusts F_t,act (p,) (N).
        joint_torques: motor torques (n,) (N m); the motors are taken as ideal.
        propeller_speed: Ω (p,) (rad/s).
        reference_speed: Ω_r (p,) of the desired thrusts, as the ESCs are told (rad/s).
        motor_current: i_m (p,) (A).
        esc: what the ESCs report (None without an ``EscSensor``).
    """

    allocation: AllocationResult
    thrust: FloatArray
    joint_torques: FloatArray
    propeller_speed: FloatArray
    reference_speed: FloatArray
    motor_current: FloatArray
    esc: EscFeedback | None = None


class ThrusterAllocator:
    """F_td = E⁺ tau_b (eq. 10), direction-preserving saturation, thruster dynamics (11-15).

    Example:
        >>> from uvms_model.thrusters import ThrusterLayout
        >>> layout = ThrusterLayout.from_parameters()
        >>> limits = layout.max_thrust_n
        >>> params = AllocatorParameters(layout.thrust_matrix(), limits, np.full(3, 100.0))
        >>> allocator = ThrusterAllocator(params)
        >>> result = allocator.allocate(np.array([50.0, 0, 0, 0, 0, 0, 1.0, 2.0, 3.0]))
        >>> (np.round(result.achieved_wrench, 9) + 0.0).tolist(), result.saturation_scale
        ([50.0, 0.0, 0.0, 0.0, 0.0, 0.0], 1.0)
    """

    def __init__(self, params: AllocatorParameters) -> None:
        self.params = params
        t = params.thrust_matrix
        self._p = params.n_thrusters
        self._n = params.n_joints
        self._t = t
        # T⁺ = Tᵀ (T Tᵀ)⁻¹, once: E⁺ = blockdiag(T⁺, I_n) because E is block diagonal.
        self._t_pinv = t.T @ np.linalg.inv(t @ t.T)
        self._t_eff = t  # T diag(η̂): T itself while every thruster is taken as healthy
        self._effectiveness = np.ones(self._p)
        self._rank = 6
        # Plant side (thruster_faults): faults of the physical thrusters, ESC telemetry.
        self.injector = ThrusterFaultInjector((), self._p)
        self.esc: EscSensor | None = None
        # Allocation side: detection on the ESC telemetry, and whether η̂ is used.
        self.detector: ThrusterFaultDetector | None = None
        self.accommodate = True
        self._inv_limit = 1.0 / params.max_thrust
        self._inv_joint = 1.0 / params.max_joint_torque
        self.thrusters = ThrusterBank(params.thruster, self._p)
        reachable = min(
            self.thrusters.max_steady_thrust(forward=True),
            self.thrusters.max_steady_thrust(forward=False),
        )
        largest = float(np.max(params.max_thrust))
        if reachable < largest:
            raise ThrusterParameterError(
                'thruster.max_motor_current_a',
                params.thruster.max_motor_current,
                f'a current that holds the largest thrust limit {largest} N forward and '
                f'reverse (it holds {reachable:.1f} N)',
            )
        # Load the compiled kernels now (a cache load, or a compilation on a cold cache), not
        # in the first control period of a real-time run; dt = 0 leaves the thrusters at rest.
        self.step(np.zeros(6 + self._n), 0.0)
        self.reset()

    @property
    def pseudo_inverse(self) -> FloatArray:
        """E⁺ (p + n, 6 + n) of eq. 10."""
        e_pinv = np.zeros((self._p + self._n, 6 + self._n))
        e_pinv[: self._p, :6] = self._t_pinv
        e_pinv[self._p :, 6:] = np.eye(self._n)
        return e_pinv

    @property
    def effectiveness(self) -> FloatArray:
        """η̂ (p,) the allocation assumes (a copy)."""
        return self._effectiveness.copy()

    @property
    def rank(self) -> int:
        """Rank of T diag(η̂): 6 while the thrusters can produce any vehicle wrench."""
        return self._rank

    @property
    def fully_actuated(self) -> bool:
        """Whether T diag(η̂) has full row rank 6."""
        return self._rank == 6

    def set_effectiveness(self, effectiveness: npt.ArrayLike) -> int:
        """Allocate on T diag(η̂) from now on (module docstring); returns its rank.

        Raises:
            ThrusterInputError: if η̂ is not p values in [0, 1].
        """
        eta = np.asarray(effectiveness, dtype=np.float64)
        if eta.shape != (self._p,) or not np.all((eta >= 0.0) & (eta <= 1.0)):
            raise ThrusterInputError(
                f'effectiveness must be {self._p} values in [0, 1], got {np.ravel(eta).tolist()}'
            )
        if np.array_equal(eta, self._effectiveness):
            return self._rank
        t = self._t
        if np.all(eta == 1.0):
            pinv, rank, t_eff = t.T @ np.linalg.inv(t @ t.T), 6, t
        else:
            pinv, rank = weighted_pseudo_inverse(t, eta)
            t_eff = t * eta[np.newaxis, :]
        self._t_pinv, self._rank, self._t_eff = pinv, rank, t_eff
        self._effectiveness = eta.copy()
        return rank

    def reset(self) -> None:
        """Stop the thrusters (zero speed, current and flow); fault declarations stay."""
        self.thrusters.reset()
        if self.detector is not None:
            self.detector.restart_model()

    def allocate(self, tau_b: npt.ArrayLike) -> AllocationResult:
        """Desired thrusts and motor torques for tau_b (6 + n,) (eq. 10), saturated by scaling.

        Raises:
            ThrusterInputError: if tau_b is not a finite (6 + n,) vector.
        """
        tau = np.asarray(tau_b, dtype=np.float64)
        if tau.shape == (6 + self._n,):
            # The matrix products stay numpy's (BLAS): the same sums, to the last bit, as
            # before the saturation moved into a kernel.
            thrust, joints = self._t_pinv @ tau[:6], np.empty(self._n)
            ok, scale, joint_scale = saturate_allocation(tau, thrust, self._inv_limit, joints,
                                                         self._inv_joint)
            if ok:
                return AllocationResult(
                    thrust=thrust,
                    joint_torques=joints,
                    achieved_wrench=self._t_eff @ thrust,
                    saturation_scale=scale,
                    joint_scale=joint_scale,
                )
        raise ThrusterInputError(
            f'tau_b must be {6 + self._n} finite values, got {np.ravel(tau).tolist()}'
        )

    def step(self, tau_b: npt.ArrayLike, dt: float, t_s: float = 0.0) -> AllocatorOutput:
        """Allocate tau_b and advance the thrusters by dt (s) toward the desired thrusts.

        The physical thrusters follow the desired thrusts through the injected faults
        (``injector``, at time t_s); the detector, if any, compares the ESC readings with its
        model and, under ``accommodate``, the next allocation runs on its η̂.

        Raises:
            ThrusterInputError: if tau_b is not a finite (6 + n,) vector or dt is negative.
        """
        allocation = self.allocate(tau_b)
        bank = self.thrusters
        demand = self.injector.motor_demand(allocation.thrust, t_s)
        thrust = bank.step(demand, dt)
        reference = bank.omega_r if demand is allocation.thrust else reference_speed(
            allocation.thrust, bank.calibration.alpha_2)
        esc = None
        if self.esc is not None:
            esc = self.esc.measure(reference, bank.omega, bank.motor_current)
            if self.detector is not None and self.detector.update(
                    allocation.thrust, esc.measured_speed, esc.measured_current, dt, t_s
            ) and self.accommodate:
                self.set_effectiveness(self.detector.effectiveness)
        return AllocatorOutput(
            allocation=allocation,
            thrust=thrust,
            joint_torques=allocation.joint_torques,
            propeller_speed=bank.omega,
            reference_speed=reference,
            motor_current=bank.motor_current,
            esc=esc,
        )
