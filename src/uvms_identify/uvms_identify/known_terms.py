"""The robot's forces that are not the hull's hydrodynamics, from its own model (uvms_model).

The robot folder's URDF and hydrodynamics file, with the hull's added mass, damping and
buoyancy set to zero, give ``M_0`` and ``bias_0`` of eq. 8: rigid bodies (vehicle and arm),
their weights, and the arm's added mass, drag and buoyancy. The identification subtracts
their vehicle rows from the thrust wrench and fits the hull's terms to what remains
(``uvms_identify.regressor``). The arm may move during an experiment: its joint angles,
rates and accelerations (the encoders) enter ``M_0`` and ``bias_0``.
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from numpy.typing import NDArray
from uvms_model.description import load_description
from uvms_model.model import UvmsModel
from uvms_model.parameters import UvmsParameters

from uvms_identify.robot_data import ROOT_LINK, RobotData

FloatArray = NDArray[np.float64]

#: The hull's entry with every hydrodynamic term zero (the known part of the model).
ZERO_HULL: dict[str, Any] = {
    'added_mass': 'coefficients', 'added_mass_kg': [0.0] * 6, 'linear_damping': [0.0] * 6,
    'quadratic_damping': [0.0] * 6, 'displaced_volume_m3': 0.0,
    'center_of_buoyancy_m': [0.0, 0.0, 0.0],
}


def model_with_hull(robot: RobotData, hull: dict[str, Any]) -> UvmsModel:
    """The robot's model (its URDF and arm links) with ``hull`` as the hull's entry."""
    tree = yaml.safe_load(robot.files.hydrodynamics.read_text(encoding='utf-8'))
    tree[ROOT_LINK] = hull
    with tempfile.TemporaryDirectory() as directory:
        path = Path(directory) / 'hydrodynamics.yaml'
        path.write_text(yaml.safe_dump(tree), encoding='utf-8')
        description = load_description(robot.files.urdf, path)
    params = UvmsParameters().updated({
        'hydrodynamics.water_density_kg_m3': robot.water_density_kg_m3,
        'hydrodynamics.gravity_m_s2': robot.gravity_m_s2,
    })
    return UvmsModel(params, description)


def hull_buoyancy_n(robot: RobotData) -> float:
    """The hull's buoyancy (N) of the robot folder's file."""
    hull = robot.hull
    if hull.get('displaced_volume_m3') is not None:
        volume = float(hull['displaced_volume_m3'])  # type: ignore[arg-type]
        return robot.water_density_kg_m3 * volume * robot.gravity_m_s2
    model = model_with_hull(robot, dict(hull))
    return float(model.hull_displaced_mass_kg) * robot.gravity_m_s2


def total_weight_n(robot: RobotData) -> float:
    """Weight of the vehicle and arm (N), from the URDF's masses."""
    model = model_with_hull(robot, ZERO_HULL)
    mass = model.mass_matrix_body(np.zeros(model.n_dof))[0, 0]
    return float(mass) * robot.gravity_m_s2


def known_forces(model: UvmsModel, attitude_rpy: FloatArray, joints: FloatArray,
                 nu: FloatArray, joint_rates: FloatArray, nu_dot: FloatArray,
                 joint_accelerations: FloatArray, rows: slice = slice(0, 6)) -> FloatArray:
    """Rows ``rows`` (vehicle: 0..5, arm: 6..) of ``M_0 w_dot + bias_0(q, w)`` per sample.

    Args:
        model: ``model_with_hull(robot, ZERO_HULL)``.
        attitude_rpy: Roll, pitch, yaw (N, 3) (rad).
        joints: Arm joint angles (N, n) (rad).
        nu: Body velocities (N, 6) (m/s, rad/s).
        joint_rates: Arm joint rates (N, n) (rad/s).
        nu_dot: Body accelerations (N, 6).
        joint_accelerations: Arm joint accelerations (N, n) (rad/s^2).
        rows: The generalized coordinates wanted: the vehicle's by default; ``slice(0,
            None)`` for all (the arm rows hold no hull term: the hull acts on the base).
    """
    n = nu.shape[0]
    out = np.empty((n, len(range(model.n_dof)[rows])))
    q = np.zeros(model.n_dof)
    w = np.zeros(model.n_dof)
    w_dot = np.zeros(model.n_dof)
    for k in range(n):
        q[3:6] = attitude_rpy[k]
        q[6:] = joints[k]
        w[:6] = nu[k]
        w[6:] = joint_rates[k]
        w_dot[:6] = nu_dot[k]
        w_dot[6:] = joint_accelerations[k]
        out[k] = (model.mass_matrix_body(q)[rows] @ w_dot + model.bias_body(q, w)[rows])
    return out


def start_joints(robot: RobotData, n_joints: int) -> FloatArray:
    """The arm's start angles of the robot folder (start.yaml), zeros if it gives none."""
    from uvms_description.robots import parameter_file_values
    values = parameter_file_values(robot.files.directory / 'start.yaml', 'simulator')
    given = values.get('initial.joint_positions')
    if given is None or len(given.value) != n_joints:
        return np.zeros(n_joints)
    return np.array(given.value, float)


def rigid_and_restoring(robot: RobotData) -> tuple[FloatArray, FloatArray]:
    """Rigid-body inertia diagonal (6,) and roll/pitch restoring stiffness (6,) at the start.

    The restoring stiffness is the slope of the gravity and buoyancy moment with roll and
    pitch of the robot folder's full model (finite difference of 0.01 rad); 0 on the others.
    """
    zero = model_with_hull(robot, ZERO_HULL)
    full = model_with_hull(robot, dict(robot.hull))
    q = np.zeros(zero.n_dof)
    q[6:] = start_joints(robot, zero.n_joints)
    inertia = np.diag(zero.mass_matrix_body(q))[:6].copy()
    restoring = np.zeros(6)
    for axis in (3, 4):
        step = 0.01
        plus, minus = q.copy(), q.copy()
        plus[axis] += step
        minus[axis] -= step
        slope = (full.gravity_body(plus)[axis] - full.gravity_body(minus)[axis]) / (2 * step)
        restoring[axis] = max(float(slope), 0.0)
    return inertia, restoring


def trim_wrench(robot: RobotData) -> FloatArray:
    """Static wrench of weight and buoyancy (6,) at level, the arm at its start pose.

    G_b of eq. 8 with the robot folder's hull (N, N m, base_link_frd): the thrust that holds
    the vehicle level and at its depth with nothing else acting.
    """
    full = model_with_hull(robot, dict(robot.hull))
    q = np.zeros(full.n_dof)
    q[6:] = start_joints(robot, full.n_joints)
    wrench: FloatArray = np.asarray(full.gravity_body(q)[:6], float)
    return wrench


def net_buoyancy_n(robot: RobotData, hull_buoyancy: float) -> float:
    """Buoyancy of hull and links minus the weight (N), level, the arm at its start pose."""
    zero = model_with_hull(robot, ZERO_HULL)
    q = np.zeros(zero.n_dof)
    q[6:] = start_joints(robot, zero.n_joints)
    return hull_buoyancy + float(zero.gravity_body(q)[2])
