"""The robot's device timing applied to what the simulator publishes and what it steps on.

One object per simulator holds the holds of ``uvms_sim.device_timing`` that the robot's
timing asks for (None where a signal is ideal, so that an ideal run takes exactly the
idealized path)::

    delivery = DeviceDelivery(devices, seed, n_joints)
    out.update(delivery.observation(seen))          # joint states, wrench as delivered
    thrusts, torques = delivery.commands(t_ns, thrusts, torques)  # as the devices apply them
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from uvms_sim.device_timing import (
    CommandHold,
    DeviceTiming,
    SampleHold,
    StaggeredHold,
    late_command_message,
)
from uvms_sim.errors import SimParameterError
from uvms_sim.plant import Observation


class DeviceDelivery:
    """Sensors sampled, delayed and held; commands latched at the devices' rates.

    Raises:
        SimParameterError: The arm's last joint's command (``latency_s`` and ``frame_s`` of
            ``arm_commands``, ``n_joints`` frames) would act a slot or more after its latch.
    """

    def __init__(self, devices: DeviceTiming, seed: int, n_joints: int) -> None:
        self._n = n_joints
        joints = devices['joint_states']
        #: One joint at a time over each round (a polled bus): joint_states.staggered.
        self._stagger_hold: StaggeredHold | None = (
            StaggeredHold(joints, n_joints, seed + 1)
            if joints.staggered and joints.rate_hz > 0.0 else None)
        self._joint_hold: SampleHold[Observation] | None = (
            None if joints.ideal or self._stagger_hold is not None
            else SampleHold(joints, seed + 1))
        self._wrench_hold: SampleHold[Observation] | None = (
            None if devices['wrench'].ideal else SampleHold(devices['wrench'], seed + 2))
        self._thrust_hold: CommandHold[Any] | None = (
            None if devices['thrusts'].rate_hz == 0.0
            else CommandHold(devices['thrusts'].rate_hz))
        arm = devices['arm_commands']
        last_joint_s = arm.latency_s + (n_joints - 1) * arm.frame_s
        if arm.frame_s > 0.0 and not last_joint_s * arm.rate_hz < 1.0:
            raise SimParameterError(late_command_message('arm_commands', last_joint_s,
                                                         arm.rate_hz))
        self._torque_hold: CommandHold[Any] | None = (
            None if arm.rate_hz == 0.0
            else CommandHold(arm.rate_hz, arm.latency_s, arm.frame_s))

    def observation(self, seen: Observation) -> Observation:
        """The observation with joint states and wrench as the devices deliver them at t_k.

        Each held signal is its newest delivered sample (uvms_sim.device_timing), stamped
        with the state's time; the ground truth (odometry, ee_pose, contact) stays current.
        """
        stagger = self._stagger_hold
        if self._joint_hold is None and self._wrench_hold is None and stagger is None:
            return seen
        n_joints = self._n
        wrench = seen if self._wrench_hold is None else self._wrench_hold.at(
            seen.t_ns, lambda: seen)
        q, w = seen.q.copy(), seen.w.copy()
        if stagger is not None:
            arm_q, arm_w, arm_tau = stagger.at(
                seen.t_ns, seen.q[6:6 + n_joints].tolist(), seen.w[6:6 + n_joints].tolist(),
                seen.joint_torques[:n_joints].tolist())
            q[6:6 + n_joints], w[6:6 + n_joints] = arm_q, arm_w
            joint_torques = seen.joint_torques.copy()
            joint_torques[:n_joints] = arm_tau
        else:
            joints = seen if self._joint_hold is None else self._joint_hold.at(
                seen.t_ns, lambda: seen)
            q[6:], w[6:] = joints.q[6:6 + n_joints], joints.w[6:6 + n_joints]
            joint_torques = joints.joint_torques
        return replace(seen, q=q, w=w, joint_torques=joint_torques,
                       sensor_force=wrench.sensor_force, sensor_torque=wrench.sensor_torque)

    def commands(self, t_ns: int, thrusts: Any, torques: Any) -> tuple[Any, Any]:
        """Thrusts as the vehicle's own loop applies them, torques as the arm bus's slots do."""
        if self._thrust_hold is not None:
            thrusts = self._thrust_hold.at(t_ns, thrusts)
        if self._torque_hold is not None:
            torques = self._torque_hold.at(t_ns, torques)
        return thrusts, torques
