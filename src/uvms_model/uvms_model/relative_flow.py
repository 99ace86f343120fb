"""The current in the dynamics: relative velocity nu_r = nu - nu_c of every body (Fossen 2011).

Fossen (2011), sec. 8.3 (the relative-velocity form of the equations of motion): with an
earth-fixed current v_c, uniform and constant (irrotational), each body's velocity relative to
the water is nu_r = nu - [R^T v_c; 0], and

    M_RB nu_dot + C_RB(nu) nu + M_A nu_r_dot + C_A(nu_r) nu_r + D(nu_r) nu_r + g(eta) = tau,

with nu_c_dot = [-omega x R^T v_c; 0] (the constant current seen from the rotating body).
Rigid body, gravity and buoyancy keep the absolute velocity. The drag terms
(``body_forces.external_forces``) read nu_r directly; the added-mass terms are in the dynamic
model itself (Pinocchio's rigid part and the sliders of ``added_mass``) with the absolute
twist, as nu x* M_A nu (Kirchhoff); ``added_mass_flow_force`` is the external force that turns
them into the relative form:

    delta = nu x* M_A nu - nu_r x* M_A nu_r + M_A nu_c_dot.

All in the body's own frame at its origin; compiled kernels on the external-force workspace.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from uvms_model.jit import kernel
from uvms_model.loop_products import matvec, spatial_cross_force

FloatArray = NDArray[np.float64]


@kernel
def flow_in_bodies(rotations: FloatArray, current_base: FloatArray, flow: FloatArray) -> None:
    """u_i = rot_body_from_base v_c (m/s) of every body into ``flow`` (n_bodies, 3).

    ``rotations`` holds rot_body_from_base of each body as rows 0-2 of a 4 x 3 block
    (``BodyForces``); ``current_base`` is v_c in base_link_frd.
    """
    for body in range(flow.shape[0]):
        for r in range(3):
            row = 4 * body + r
            flow[body, r] = (rotations[row, 0] * current_base[0]
                             + rotations[row, 1] * current_base[1]
                             + rotations[row, 2] * current_base[2])


@kernel
def added_mass_flow_force(
    twists: FloatArray, flow: FloatArray, bodies: NDArray[np.intp], matrices: FloatArray,
    forces: FloatArray,
) -> None:
    """Add delta = nu x* M_A nu - nu_r x* M_A nu_r + M_A nu_c_dot to each listed body's force.

    Args:
        twists: The bodies' twists nu (6 per body, own frames).
        flow: The current u_i in each body's frame (n_bodies, 3).
        bodies: The bodies with added mass.
        matrices: Their M_A (len(bodies), 6, 6) at the body origin, body axes.
        forces: The bodies' external forces (6 per body), added to.
    """
    for k in range(bodies.shape[0]):
        body = bodies[k]
        base = 6 * body
        nu = np.empty(6)
        nu_r = np.empty(6)
        nu_c_dot = np.zeros(6)
        for i in range(6):
            nu[i] = twists[base + i]
            nu_r[i] = nu[i]
        for i in range(3):
            nu_r[i] -= flow[body, i]
            j, m = (i + 1) % 3, (i + 2) % 3
            nu_c_dot[i] = -(nu[3 + j] * flow[body, m] - nu[3 + m] * flow[body, j])
        mass = matrices[k]
        absolute = spatial_cross_force(nu, matvec(mass, nu))
        relative = spatial_cross_force(nu_r, matvec(mass, nu_r))
        acceleration = matvec(mass, nu_c_dot)
        for i in range(6):
            forces[base + i] += absolute[i] - relative[i] + acceleration[i]
