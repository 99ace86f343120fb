"""The twins' physics: PWM on the vehicle's outputs to thrust, motor current to joint torque."""

from __future__ import annotations

import numpy as np
import pytest
from uvms_hardware.reach_protocol import Mode
from uvms_hardware.t200_curve import clamp_pwm
from uvms_twins.plant_side import ThrusterTwin, effort_limits_n_m, joint_torques

ROBOT = 'bluerov2_alpha5'


def settle(twin: ThrusterTwin, outputs_us: list[int], seconds: float = 2.0) -> np.ndarray:
    """Thrusts after the propellers had ``seconds`` at these outputs (500 Hz steps)."""
    thrust = np.zeros(len(twin.channels))
    for _ in range(round(seconds / 0.002)):
        thrust = twin.step(outputs_us, 16.0, 0.002)
    return thrust


def test_neutral_and_absent_pulses_make_no_thrust() -> None:
    """1500 us is neutral; an output with no pulse (0) is a stopped ESC."""
    twin = ThrusterTwin.for_robot(ROBOT)
    np.testing.assert_allclose(settle(twin, [1500] * 8 + [0] * 8), 0.0, atol=1e-9)
    np.testing.assert_allclose(settle(twin, [0] * 16), 0.0, atol=1e-9)


def test_the_bridges_pwm_becomes_the_thrust_it_asked_for() -> None:
    """Thrust -> PWM (the bridge's curve, whole us) -> thrust (the twin) within 2 %."""
    twin = ThrusterTwin.for_robot(ROBOT)
    wanted = np.array([10.0, -10.0, 25.0, -25.0, 5.0, -5.0, 30.0, 0.0])
    outputs = [1500] * 16
    for thrust, channel in zip(wanted, twin.channels, strict=True):
        outputs[channel - 1] = clamp_pwm(twin.curve.pwm_from_thrust(thrust, 16.0))
    np.testing.assert_allclose(settle(twin, outputs), wanted, rtol=0.02, atol=0.05)


def test_the_propellers_take_time_to_spin_up() -> None:
    """A step to full forward is not full thrust in the first step (eq. 11-15)."""
    twin = ThrusterTwin.for_robot(ROBOT)
    first = twin.step([1900] * 8 + [0] * 8, 16.0, 0.002)
    assert np.all(first < 0.5 * twin.desired_thrust_n([1900] * 8 + [0] * 8, 16.0))


def test_a_reversed_thruster_pushes_the_other_way() -> None:
    """Direction -1 on the frame: the same pulse gives the opposite thrust."""
    twin = ThrusterTwin.for_robot(ROBOT)
    twin.directions = (-1.0, *twin.directions[1:])
    desired = twin.desired_thrust_n([1700] * 8 + [0] * 8, 16.0)
    assert desired[0] == pytest.approx(-desired[1])


def test_only_current_mode_makes_torque_within_the_effort_limit() -> None:
    """Current -> I Kt N eta clamped at the URDF's effort; other modes are limp."""
    limits = effort_limits_n_m(ROBOT)
    commands = {'joint_1': (Mode.CURRENT, 0.0), 'joint_2': (Mode.CURRENT, 0.0),
                'joint_3': (Mode.VELOCITY, 0.0), 'joint_4': (Mode.STANDBY, 0.0)}
    torques = joint_torques(commands, {'joint_1': 2.0, 'joint_2': 50.0, 'joint_3': None,
                                       'joint_4': None}, limits)
    assert torques == {'joint_1': 2.0, 'joint_2': limits['joint_2'], 'joint_3': 0.0,
                       'joint_4': 0.0}
    assert limits['joint_2'] == 9.0
