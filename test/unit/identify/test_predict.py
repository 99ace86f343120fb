"""Held-out prediction: the velocity a hull model predicts, attitude integrated with it.

The robot folder's own model (the simulator's) is stepped with its own hull; the predictor
starts from one of its states and runs over 10 s with the thrusts and the arm as inputs.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from uvms_identify.known_terms import ZERO_HULL, model_with_hull, start_joints
from uvms_identify.predict import rotation_step, simulate
from uvms_identify.recording import Series
from uvms_identify.robot_data import RobotData, load_robot
from uvms_identify.signals import rpy_matrix

ROBOT = 'bluerov2_alpha5'
DT = 0.002
EVERY = 10  # the predictor's grid: 50 Hz


@pytest.fixture(scope='module')
def robot() -> RobotData:
    """The shipped BlueROV2 Heavy + Alpha 5 folder."""
    return load_robot(ROBOT)


def _run(robot: RobotData, duration_s: float, disturbance: np.ndarray) -> Series:
    """The robot under a roll/pitch/yaw thrust wave and ``disturbance`` (6,), unrecorded."""
    model = model_with_hull(robot, dict(robot.hull))
    q = np.zeros(model.n_dof)
    q[2] = 2.0
    q0 = start_joints(robot, model.n_joints)
    q[6:] = q0
    w = np.zeros(model.n_dof)
    t = np.arange(0.0, duration_s, DT)
    wrench = np.column_stack([np.zeros((t.size, 3)), 0.2 * np.sin(0.9 * t),
                              0.3 * np.sin(0.7 * t + 1.0), 0.6 * np.sin(0.5 * t)])
    qs, ws = np.empty((t.size, model.n_dof)), np.empty((t.size, model.n_dof))
    for k in range(t.size):
        qs[k], ws[k] = q, w
        tau = np.zeros(model.n_dof)
        tau[:6] = wrench[k] + disturbance
        tau[6:] = -2.0 * (q[6:] - q0) - 0.1 * w[6:]
        q, w = model.step(q, w, tau, None, DT)
    grid = slice(0, t.size, EVERY)
    n = model.n_joints
    rotations = np.array([rpy_matrix(*angles) for angles in qs[grid, 3:6]])
    nu = ws[grid, :6]
    joint_rates = ws[grid, 6:]
    return Series(Path('synthetic'), t[grid], nu, np.gradient(nu, DT * EVERY, axis=0),
                  qs[grid, 3:6], rotations[:, 2, :], qs[grid, 6:], joint_rates,
                  np.gradient(joint_rates, DT * EVERY, axis=0), wrench[grid],
                  np.zeros((nu.shape[0], n)), qs[grid, 2], np.ones(nu.shape[0], bool),
                  np.zeros((nu.shape[0], n)))


def test_rotation_step_is_the_exponential_of_the_body_rates() -> None:
    """A turn of 0.3 rad/s about z for 1 s is a yaw of 0.3 rad; no rate, no turn."""
    assert np.allclose(rotation_step(np.array([0.0, 0.0, 0.3]), 1.0),
                       rpy_matrix(0.0, 0.0, 0.3), atol=1e-15)
    assert np.array_equal(rotation_step(np.zeros(3), 0.02), np.eye(3))


def test_the_true_hull_predicts_the_vehicle_over_10_s(robot: RobotData) -> None:
    """From a recorded state, the robot's own hull predicts its velocity 10 s later."""
    series = _run(robot, 12.0, np.zeros(6))
    model = model_with_hull(robot, ZERO_HULL)
    predicted = simulate(model, robot.prior_theta(), series, 50, 500)
    error = predicted[-1] - series.nu[550]
    assert np.all(np.abs(error[3:]) < 0.01), error
    assert np.all(np.abs(error[:3]) < 0.01), error


def test_an_unrecorded_torque_does_not_integrate_over_the_horizon(robot: RobotData) -> None:
    """A 0.03 N m roll and pitch torque the recording does not hold (the arm's, a thruster's).

    The vehicle takes it on a tilt of its restoring moment; the prediction, with the
    attitude integrated, tilts the other way and its rate error stays that of a swing (old
    predictor, attitude as recorded: the restoring moment of the recorded tilt stood
    unbalanced for the whole horizon, a roll-rate error of 0.1 rad/s after 10 s).
    """
    disturbance = np.array([0.0, 0.0, 0.0, 0.03, 0.03, 0.0])
    series = _run(robot, 22.0, disturbance)
    model = model_with_hull(robot, ZERO_HULL)
    errors = np.array([simulate(model, robot.prior_theta(), series, start, 500)[-1]
                       - series.nu[start + 500] for start in range(250, 551, 50)])
    rms = np.sqrt(np.mean(errors**2, axis=0))
    assert rms[3] < 0.02 and rms[4] < 0.02, rms
