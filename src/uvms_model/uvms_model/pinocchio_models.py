"""The two Pinocchio models of the UVMS, built once from the URDF (free-flyer root + arm).

- The *kinematic* model is the URDF as written (frames ``base_link_frd``, the arm links,
  ``ee_link``, ``ft_sensor_link``); its free-flyer velocity is the body twist [v; omega] in
  ``base_link_frd``, the first six quasi-velocities w of eq. 8.
- The *dynamic* model adds the added mass of the water each body entrains (Kirchhoff: M_A is
  part of the body's inertia). Each body carries its rigid inertia plus the rigid part of its
  added mass (mass a_ax at the shape's centre with the rotary terms); the lateral excess
  a_lat - a_ax sits as a point mass on a frictionless *slider* (a prismatic joint along the
  shape's axis e) held at rest. A free slider at zero speed transmits no axial force:
  eliminating its acceleration leaves exactly the lateral-only inertia (a_lat - a_ax)(I - e e^T)
  at c, so ABA, CRBA and RNEA of this model give M_b = M_RB + sum_i J_i^T M_A,i J_i (eq. 8)
  with no approximation. Gravity is off: net weights enter as external forces.

Joint order of the dynamic model: the hull and the arm links first (so w, tau_b and w_dot are
its first 6 + n velocities), then the sliders from the tip's down to the hull's. That order is
depth-first (every joint's subtree is one span of joints and of velocities: in the paper's
arm, link_2's subtree is link_2, link_3, link_3's slider, link_2's slider), which CRBA
requires; so one model and one workspace serve ABA, RNEA and CRBA.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import numpy as np
import pinocchio as pin  # type: ignore[import-untyped]
from numpy.typing import NDArray

from uvms_model.added_mass import AddedMass
from uvms_model.description import RobotDescription
from uvms_model.errors import DescriptionError, ModelError

FloatArray = NDArray[np.float64]

def kinematic_model(description: RobotDescription) -> pin.Model:
    """Pinocchio model of the URDF as written, free-flyer root (base_link_frd).

    Raises:
        DescriptionError: If Pinocchio cannot read the URDF, or joints or frames differ.
    """
    try:
        model = pin.buildModelFromXML(description.urdf_text, pin.JointModelFreeFlyer())
    except (ValueError, RuntimeError) as exc:
        raise DescriptionError(
            f'{description.urdf_path}: Pinocchio cannot build a model: {exc}'
        ) from exc
    names = tuple(model.names)[2:]
    if names != description.joint_names:
        raise DescriptionError(
            f'{description.urdf_path}: Pinocchio found the joints {list(names)}, expected '
            f'{list(description.joint_names)}'
        )
    for frame in description.frame_names:
        if not model.existFrame(frame):
            raise DescriptionError(f"{description.urdf_path}: no frame '{frame}'")
    return model


def dynamic_model(
    description: RobotDescription, kin: pin.Model, added: Sequence[AddedMass | None]
) -> tuple[pin.Model, list[int], list[int]]:
    """Pinocchio model of the rigid bodies with their added mass (rigid part + slider).

    Args:
        description: The robot description (for error messages).
        kin: The kinematic model.
        added: Added mass of the hull and each arm link (None: none).

    Returns:
        The model, the joints of the hull and the arm links, and the sliders' joints (tip
        first).

    Raises:
        DescriptionError: For an axial added mass above the lateral one (an oblate shape).
    """
    dyn = pin.Model()
    dyn.gravity = pin.Motion.Zero()  # gravity and buoyancy are external forces
    new_id = {0: 0}
    bodies: list[int] = []
    pending: list[tuple[int, AddedMass]] = []
    for i in range(1, kin.njoints):
        joint = dyn.addJoint(
            new_id[kin.parents[i]], kin.joints[i], kin.jointPlacements[i], kin.names[i]
        )
        new_id[i] = joint
        dyn.appendBodyToJoint(joint, kin.inertias[i], pin.SE3.Identity())
        bodies.append(joint)
        body_added = added[i - 1]
        if body_added is None:
            continue
        dyn.appendBodyToJoint(
            joint,
            pin.Inertia(body_added.axial_kg, body_added.center, body_added.rigid_rotary()),
            pin.SE3.Identity(),
        )
        if body_added.lateral_kg < body_added.axial_kg:
            raise DescriptionError(
                f'{description.urdf_path}: body of {kin.names[i]}: axial added mass above '
                'the lateral one (an oblate shape) is not supported'
            )
        if body_added.lateral_kg > body_added.axial_kg:
            pending.append((joint, body_added))
    sliders: list[int] = []
    for joint, body_added in reversed(pending):  # the tip's first: depth-first order
        slider = dyn.addJoint(
            joint,
            pin.JointModelPrismaticUnaligned(body_added.axis),
            pin.SE3(np.eye(3), body_added.center),
            f'{dyn.names[joint]}_added_mass_slider',
        )
        excess = body_added.lateral_kg - body_added.axial_kg
        dyn.appendBodyToJoint(
            slider, pin.Inertia(excess, np.zeros(3), np.zeros((3, 3))), pin.SE3.Identity()
        )
        sliders.append(slider)
    _check_depth_first(description, dyn)
    return dyn, bodies, sliders


def _check_depth_first(description: RobotDescription, model: pin.Model) -> None:
    """Raise unless every joint's subtree is the span of joints up to its last descendant."""
    last = list(range(model.njoints))
    for i in range(model.njoints - 1, 0, -1):
        parent = model.parents[i]
        last[parent] = max(last[parent], last[i])
    for i in range(1, model.njoints):
        for j in range(i + 1, last[i] + 1):
            ancestor = j
            while ancestor > i:
                ancestor = model.parents[ancestor]
            if ancestor != i:
                raise DescriptionError(
                    f'{description.urdf_path}: the joints are not in depth-first order '
                    f'({model.names[j]} lies inside the subtree of {model.names[i]})'
                )


def strided_rows(elements: Sequence[FloatArray], width: int) -> FloatArray:
    """One (n, width) view over equally spaced per-joint Eigen vectors of a Pinocchio Data.

    Pinocchio stores a joint quantity (twists, placements, forces) in one std::vector, so the
    rows lie at a fixed stride; a view over all of them reads or writes every joint in one
    numpy operation. The addresses are checked: a layout that is not a plain array raises.

    Raises:
        ModelError: If the vectors are not equally spaced or not contiguous.
    """
    addresses = [array.__array_interface__['data'][0] for array in elements]
    stride = addresses[1] - addresses[0] if len(addresses) > 1 else 8 * width
    if any(b - a != stride for a, b in itertools.pairwise(addresses)) or any(
        array.strides[0] != 8 for array in elements
    ):
        raise ModelError('Pinocchio data is not laid out as one array per quantity')
    view: FloatArray = np.lib.stride_tricks.as_strided(
        elements[0], shape=(len(elements), width), strides=(stride, 8), writeable=True
    )
    return view
