"""Robot description of the UVMS: its URDF and the hydrodynamic parameters beside it.

The URDF (``uvms_description/urdf/uvms.urdf``) is the one source of the kinematics and the
rigid-body inertia; Pinocchio builds its models from the same text
(``uvms_model.pinocchio_models``). This module reads what Pinocchio does not: the collision
geometry that sizes the hydrodynamics (the hull ellipsoid, the link cylinders), and the
hydrodynamic parameters in ``uvms_description/config/hydrodynamics.yaml``, keyed by link name.
It also checks what the model relies on before Pinocchio sees the file, so that a missing
file, malformed XML, a broken tree or a missing frame stops start-up with one line naming the
file and the element.

The URDF has no ellipsoid primitive: the hull is the mesh ``meshes/unit_sphere.stl`` (a
sphere of diameter 1 m) scaled to the ellipsoid's diameters, ``scale="1.0 0.5 0.5"``.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from uvms_model.errors import DescriptionError
from uvms_model.hydrodynamics_file import (
    HullHydrodynamics,
    LinkHydrodynamics,
    read_hydrodynamics,
)

FloatArray = NDArray[np.float64]

ROOT_LINK = 'base_link_frd'
EE_LINK = 'ee_link'
SENSOR_LINK = 'ft_sensor_link'
REQUIRED_LINKS = (ROOT_LINK, EE_LINK, SENSOR_LINK)
"""Links the project names (its frames): the URDF must have every one."""
MIN_ARM_JOINTS = 3
"""Fewest revolute arm joints: the task space X is 3-D (paper eq. 20-22)."""
UNIT_SPHERE_MESH = 'unit_sphere.stl'
"""File name of the sphere mesh (diameter 1 m) that a scale turns into an ellipsoid."""



@dataclass(frozen=True)
class Ellipsoid:
    """Ellipsoid in its link's frame: semi-axes (m) along its own axes, centre and rotation."""

    semi_axes_m: tuple[float, float, float]
    center_m: tuple[float, float, float]
    rotation: tuple[float, ...]  # rot_link_from_shape, row-major 3 x 3


@dataclass(frozen=True)
class Cylinder:
    """Cylinder in its link's frame: radius, length, centre and unit axis (URDF: shape z)."""

    radius_m: float
    length_m: float
    center_m: tuple[float, float, float]
    rotation: tuple[float, ...]  # rot_link_from_shape, row-major; column 2 is the axis

    @property
    def axis(self) -> FloatArray:
        """Unit axis of the cylinder in the link frame (the shape frame's z)."""
        return np.reshape(self.rotation, (3, 3))[:, 2].copy()

    @property
    def volume_m3(self) -> float:
        """Pi r^2 L (m^3)."""
        return math.pi * self.radius_m**2 * self.length_m


@dataclass(frozen=True)
class RobotDescription:
    """What the model reads from the URDF and the hydrodynamics file, checked.

    Attributes:
        urdf_path: The URDF file.
        hydrodynamics_path: The hydrodynamic parameters file.
        urdf_text: The URDF as read (Pinocchio builds its model from it).
        joint_names: The arm's revolute joints, base to tip (n >= 3).
        link_names: The arm links, each the child of one arm joint, base to tip.
        hull: The hull ellipsoid (collision geometry of ``base_link_frd``); None for a hull
            given by coefficients.
        links: The collision cylinders of the arm links.
        ee_offset_m: Position of ``ee_link`` in the last arm link (m).
        hull_hydrodynamics: Parameters of the hull.
        link_hydrodynamics: Parameters of each arm link.
    """

    urdf_path: Path
    hydrodynamics_path: Path
    urdf_text: str
    joint_names: tuple[str, ...]
    link_names: tuple[str, ...]
    hull: Ellipsoid | None
    links: tuple[Cylinder, ...]
    ee_offset_m: tuple[float, float, float]
    hull_hydrodynamics: HullHydrodynamics
    link_hydrodynamics: tuple[LinkHydrodynamics, ...]

    @property
    def n_joints(self) -> int:
        """n, the number of arm joints."""
        return len(self.joint_names)

    @property
    def frame_names(self) -> tuple[str, ...]:
        """The frames the model poses: root, arm links, end effector, sensor."""
        return (ROOT_LINK, *self.link_names, EE_LINK, SENSOR_LINK)


def _default_paths() -> tuple[Path, Path]:
    """The URDF and hydrodynamics file of the uvms_description package."""
    try:
        import uvms_description
    except ImportError as exc:  # pragma: no cover - uvms_description ships with uvms_model
        msg = f'uvms_description is not importable ({exc}); give description.urdf_path'
        raise DescriptionError(msg) from exc
    try:
        return uvms_description.urdf_path(), uvms_description.hydrodynamics_path()
    except FileNotFoundError as exc:
        raise DescriptionError(str(exc)) from exc


def _urdf_text(path: Path) -> str:
    """The URDF as text, a ``.xacro`` file expanded (``uvms_description.robots.urdf_text``)."""
    from uvms_description.robots import RobotFolderError, urdf_text

    try:
        return urdf_text(path)
    except RobotFolderError as exc:
        raise DescriptionError(str(exc)) from exc


def _read(path: Path, what: str) -> str:
    try:
        return path.read_text(encoding='utf-8')
    except OSError as exc:
        raise DescriptionError(f'{path}: cannot read the {what}: {exc.strerror or exc}') from exc


def _floats(path: Path, where: str, name: str, text: str | None, count: int) -> list[float]:
    """Parse ``count`` space-separated numbers of an attribute, or raise naming it."""
    if text is None:
        raise DescriptionError(f"{path}: {where}: attribute '{name}' is missing")
    try:
        values = [float(item) for item in text.split()]
    except ValueError:
        values = []
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise DescriptionError(
            f"{path}: {where}: attribute '{name}' = '{text}' must be {count} finite number(s)"
        )
    return values


def _rotation_from_rpy(roll: float, pitch: float, yaw: float) -> FloatArray:
    """URDF's fixed-axis roll-pitch-yaw, Rz(yaw) Ry(pitch) Rx(roll); cos(pi/2) snapped to 0."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    rot = np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )
    # rpy = (0, 1.5707963267948966, 0) gives entries of 6e-17: they mean exact zeros.
    rot[np.abs(rot) < 1e-12] = 0.0
    return rot


def _origin(path: Path, where: str, element: ET.Element) -> tuple[FloatArray, FloatArray]:
    """(xyz, rotation) of an ``<origin>`` child (identity when absent)."""
    origin = element.find('origin')
    if origin is None:
        return np.zeros(3), np.eye(3)
    xyz = _floats(path, f'{where} <origin>', 'xyz', origin.get('xyz', '0 0 0'), 3)
    rpy = _floats(path, f'{where} <origin>', 'rpy', origin.get('rpy', '0 0 0'), 3)
    return np.array(xyz), _rotation_from_rpy(*rpy)


def _collision_geometry(
    path: Path, link: ET.Element, name: str
) -> tuple[str, ET.Element, FloatArray, FloatArray]:
    """(shape tag, shape element, centre, rotation) of a link's single collision geometry."""
    collisions = link.findall('collision')
    if len(collisions) != 1:
        raise DescriptionError(
            f"{path}: link '{name}' has {len(collisions)} <collision> elements, expected 1 "
            '(it sizes the added mass, buoyancy and drag)'
        )
    where = f"link '{name}' <collision>"
    geometry = collisions[0].find('geometry')
    if geometry is None or len(geometry) != 1:
        raise DescriptionError(f'{path}: {where}: expected one shape in <geometry>')
    center, rotation = _origin(path, where, collisions[0])
    return geometry[0].tag, geometry[0], center, rotation


def _hull(path: Path, link: ET.Element) -> Ellipsoid:
    tag, shape, center, rotation = _collision_geometry(path, link, ROOT_LINK)
    where = f"link '{ROOT_LINK}' <collision><geometry><{tag}>"
    if tag == 'sphere':
        radius = _floats(path, where, 'radius', shape.get('radius'), 1)[0]
        semi = (radius, radius, radius)
    elif tag == 'mesh' and Path(shape.get('filename', '')).name == UNIT_SPHERE_MESH:
        scale = _floats(path, where, 'scale', shape.get('scale', '1 1 1'), 3)
        semi = (0.5 * scale[0], 0.5 * scale[1], 0.5 * scale[2])
    else:
        raise DescriptionError(
            f"{path}: {where}: the hull must be a <sphere> or the mesh {UNIT_SPHERE_MESH} "
            "scaled to the ellipsoid's diameters (URDF has no ellipsoid)"
        )
    if min(semi) <= 0.0:
        raise DescriptionError(f'{path}: {where}: semi-axes {list(semi)} must be positive')
    if np.abs(center).max() > 0.0 or np.abs(rotation - np.eye(3)).max() > 0.0:
        raise DescriptionError(
            f'{path}: {where}: the hull must be centred on {ROOT_LINK} with its axes (the body '
            'frame of eq. 8 is the hull centre)'
        )
    return Ellipsoid(semi, (0.0, 0.0, 0.0), tuple(np.eye(3).ravel().tolist()))


def _cylinder(path: Path, link: ET.Element, name: str) -> Cylinder:
    tag, shape, center, rotation = _collision_geometry(path, link, name)
    where = f"link '{name}' <collision><geometry><{tag}>"
    if tag != 'cylinder':
        raise DescriptionError(f'{path}: {where}: an arm link must be a <cylinder>')
    radius = _floats(path, where, 'radius', shape.get('radius'), 1)[0]
    length = _floats(path, where, 'length', shape.get('length'), 1)[0]
    if radius <= 0.0 or length <= 2.0 * radius:
        raise DescriptionError(
            f'{path}: {where}: radius {radius!r} m and length {length!r} m must describe a '
            'slender cylinder (length > 2 radius > 0; strip theory)'
        )
    return Cylinder(
        radius,
        length,
        (float(center[0]), float(center[1]), float(center[2])),
        tuple(rotation.ravel().tolist()),
    )


def _check_tree(path: Path, robot: ET.Element) -> tuple[dict[str, ET.Element], list[ET.Element]]:
    """check_urdf's rules: named links, joints whose parent and child exist, one root."""
    links: dict[str, ET.Element] = {}
    for link in robot.findall('link'):
        name = link.get('name')
        if not name:
            raise DescriptionError(f'{path}: a <link> has no name')
        if name in links:
            raise DescriptionError(f"{path}: link '{name}' is defined twice")
        links[name] = link
    joints = robot.findall('joint')
    children: dict[str, str] = {}
    for joint in joints:
        name = joint.get('name') or '?'
        for role in ('parent', 'child'):
            element = joint.find(role)
            target = None if element is None else element.get('link')
            if target is None:
                raise DescriptionError(f"{path}: joint '{name}' has no <{role} link=...>")
            if target not in links:
                raise DescriptionError(
                    f"{path}: joint '{name}': {role} link '{target}' is not defined"
                )
        child = joint.find('child').get('link')  # type: ignore[union-attr]
        if child in children:
            raise DescriptionError(
                f"{path}: link '{child}' is the child of two joints "
                f"('{children[child]}' and '{name}')"
            )
        children[child] = name  # type: ignore[index]
    roots = [name for name in links if name not in children]
    if len(roots) != 1:
        raise DescriptionError(f'{path}: expected one root link, found {roots}')
    if roots[0] != ROOT_LINK:
        raise DescriptionError(f"{path}: the root link is '{roots[0]}', expected '{ROOT_LINK}'")
    for name in REQUIRED_LINKS:
        if name not in links:
            raise DescriptionError(f"{path}: link '{name}' is missing (a frame of the project)")
    return links, joints


def _check_masses(path: Path, links: Mapping[str, ET.Element], required: tuple[str, ...]) -> None:
    """Every ``<mass value>`` positive; the root and the arm links must have one."""
    for name, link in links.items():
        mass = link.find('inertial/mass')
        if mass is None:
            if name in required:
                raise DescriptionError(f"{path}: link '{name}' has no <inertial><mass>")
            continue
        value = _floats(path, f"link '{name}' <inertial><mass>", 'value', mass.get('value'), 1)[0]
        if value <= 0.0:
            raise DescriptionError(
                f"{path}: link '{name}' <inertial><mass value='{mass.get('value')}'>: "
                'the mass must be positive'
            )


def _arm_chain(
    path: Path, joints: list[ET.Element]
) -> tuple[tuple[str, ...], tuple[str, ...], tuple[float, float, float]]:
    """The arm: its revolute joints and their child links, base to tip, and the EE offset.

    The arm is the path of joints from the root to ``ee_link``: its revolute joints are the
    arm joints (at least ``MIN_ARM_JOINTS``), fixed joints may sit anywhere on it. Any other
    movable joint in the file would be a branch Pinocchio turns into extra coordinates.
    """
    by_child = {j.find('child').get('link'): j for j in joints}  # type: ignore[union-attr]
    chain: list[ET.Element] = []
    link = EE_LINK
    while link in by_child:
        joint = by_child[link]
        chain.append(joint)
        link = joint.find('parent').get('link')  # type: ignore[union-attr,assignment]
    chain.reverse()
    for joint in chain:
        if joint.get('type') not in ('revolute', 'fixed'):
            raise DescriptionError(
                f"{path}: joint '{joint.get('name')}' on the arm ({ROOT_LINK} to {EE_LINK}) is "
                f"of type '{joint.get('type')}'; the arm takes revolute and fixed joints"
            )
    on_path = {str(j.get('name')) for j in chain}
    for joint in joints:
        if joint.get('type') != 'fixed' and joint.get('name') not in on_path:
            raise DescriptionError(
                f"{path}: joint '{joint.get('name')}' ({joint.get('type')}) is not on the arm "
                f'from {ROOT_LINK} to {EE_LINK}: a branched chain (only fixed joints may '
                'branch off)'
            )
    movable = [j for j in chain if j.get('type') == 'revolute']
    names = tuple(str(j.get('name')) for j in movable)
    if len(movable) < MIN_ARM_JOINTS:
        raise DescriptionError(
            f'{path}: the arm from {ROOT_LINK} to {EE_LINK} has {len(movable)} revolute '
            f'joints {list(names)}; at least {MIN_ARM_JOINTS} are needed (a 3-D task space)'
        )
    link_names = tuple(str(j.find('child').get('link')) for j in movable)  # type: ignore[union-attr]
    offset = np.zeros(3)
    rotation = np.eye(3)
    for joint in chain[chain.index(movable[-1]) + 1:]:
        xyz, rot = _origin(path, f"joint '{joint.get('name')}'", joint)
        offset = offset + rotation @ xyz
        rotation = rotation @ rot
    link = SENSOR_LINK
    while link in by_child and link != link_names[-1]:
        joint = by_child[link]
        if joint.get('type') != 'fixed':
            link = ''
            break
        link = joint.find('parent').get('link')  # type: ignore[union-attr,assignment]
    if link != link_names[-1]:
        raise DescriptionError(
            f"{path}: '{SENSOR_LINK}' must hang below the last arm link "
            f"'{link_names[-1]}' by fixed joints"
        )
    return names, link_names, (float(offset[0]), float(offset[1]), float(offset[2]))


def load_description(
    urdf_path: str | Path | None = None, hydrodynamics_path: str | Path | None = None
) -> RobotDescription:
    """Read and check the URDF and the hydrodynamic parameters of the UVMS.

    Args:
        urdf_path: The URDF; None or '' for uvms_description's ``urdf/uvms.urdf``.
        hydrodynamics_path: The hydrodynamic parameters; None or '' for uvms_description's
            ``config/hydrodynamics.yaml``.

    Raises:
        DescriptionError: For a missing or malformed file, a broken tree (a joint whose
            parent or child does not exist, several roots), a missing frame, an arm of fewer
            than 3 revolute joints, a branched chain, a mass that is not positive, collision
            geometry the hydrodynamics cannot size, or a bad hydrodynamic parameter. The
            one-line message names the file and the element.
    """
    default_urdf, default_hydro = (None, None)
    if not urdf_path or not hydrodynamics_path:
        default_urdf, default_hydro = _default_paths()
    urdf = Path(urdf_path) if urdf_path else default_urdf
    hydro = Path(hydrodynamics_path) if hydrodynamics_path else default_hydro
    assert urdf is not None and hydro is not None
    text = _urdf_text(urdf)
    try:
        robot = ET.fromstring(text)
    except ET.ParseError as exc:
        raise DescriptionError(f'{urdf}: malformed URDF (XML): {exc}') from exc
    if robot.tag != 'robot':
        raise DescriptionError(f'{urdf}: the root element is <{robot.tag}>, expected <robot>')
    links, joints = _check_tree(urdf, robot)
    joint_names, link_names, ee_offset = _arm_chain(urdf, joints)
    _check_masses(urdf, links, (ROOT_LINK, *link_names))
    hull_params, link_params = read_hydrodynamics(hydro, ROOT_LINK, link_names)
    return RobotDescription(
        urdf_path=urdf,
        hydrodynamics_path=hydro,
        urdf_text=text,
        joint_names=joint_names,
        link_names=link_names,
        hull=None if hull_params.added_mass == 'coefficients' else _hull(urdf, links[ROOT_LINK]),
        links=tuple(_cylinder(urdf, links[name], name) for name in link_names),
        ee_offset_m=ee_offset,
        hull_hydrodynamics=hull_params,
        link_hydrodynamics=link_params,
    )
