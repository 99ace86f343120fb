"""A robot's hardware constants: ``hardware.yaml`` of its folder plus the URDF's joint limits.

Pure Python (no rclpy). The Alpha 5 bridge and twin both read the arm's drives from here, so
the device ids, limits and the torque <-> current relation exist once::

    arm = load_alpha5('bluerov2_alpha5')          # joints base to wrist, URDF limits
    current_ma = arm.joints[0].current_ma(2.0)     # 2 N m at joint_1 as motor current

Joint torque and motor current: tau_joint = I * Kt * gear_ratio * efficiency (Reach's
datasheet constants). The same efficiency is used both ways (driving and back-driving);
the datasheet gives one figure.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml
from uvms_model.description import load_description
from uvms_model.errors import DescriptionError

from uvms_description.robots import RobotFolderError, robot_files, urdf_text
from uvms_hardware.errors import HardwareError

#: The robot folder's hardware file.
HARDWARE_FILE = 'hardware.yaml'
_MA_PER_A = 1000.0


class HardwareConfigError(HardwareError, ValueError):
    """A hardware file or URDF that lacks or misstates what a bridge needs (file, key named)."""


@dataclass(frozen=True)
class Spec:
    """A bridge parameter: name, default, description with its unit, valid range."""

    name: str
    default: Any
    description: str
    min_value: float | None = None
    max_value: float | None = None


@dataclass(frozen=True)
class Drive:
    """One Alpha 5 device as a joint of the robot.

    Attributes:
        joint_name: The URDF joint (or the jaw's name given to the bridge).
        device_id: Its id on the bus (0x01-0x05).
        axis: Reach's letter (A-E).
        position_limits: (lower, upper) in rad, or m for the jaws.
        velocity_limit: Largest speed in rad/s, or m/s for the jaws.
        current_limit_ma: Largest motor current (mA).
        torque_per_ma_n_m: Joint torque per mA of motor current (Kt * ratio * efficiency
            / 1000); 0 where the constants are not published (the jaws).
    """

    joint_name: str
    device_id: int
    axis: str
    position_limits: tuple[float, float]
    velocity_limit: float
    current_limit_ma: float
    torque_per_ma_n_m: float

    def current_ma(self, torque_n_m: float) -> float:
        """Motor current (mA) giving ``torque_n_m`` at the joint, clamped at the limit."""
        if self.torque_per_ma_n_m <= 0.0:
            return 0.0
        current = torque_n_m / self.torque_per_ma_n_m
        return max(-self.current_limit_ma, min(self.current_limit_ma, current))

    def torque_n_m(self, current_ma: float) -> float:
        """Joint torque (N m) of a motor current (mA)."""
        return current_ma * self.torque_per_ma_n_m


@dataclass(frozen=True)
class Alpha5Hardware:
    """The arm's drives: ``joints`` base to wrist (URDF order), ``jaw`` if it is driven.

    ``jaw_device`` is the jaws' device as the hardware file describes it (``alpha5.jaw``),
    driven or not: the twin serves it whenever the arm has it, as a real Alpha 5 does.
    """

    joints: tuple[Drive, ...]
    jaw: Drive | None
    udp_port: int
    serial_baud: int
    jaw_device: Drive | None = None

    @property
    def drives(self) -> tuple[Drive, ...]:
        """Every driven device: the joints, then the jaw."""
        return self.joints + ((self.jaw,) if self.jaw is not None else ())


@dataclass(frozen=True)
class NetFtHardware:
    """The Net F/T box as the hardware file gives it: RDT port, calibration, RDT rate.

    Attributes:
        port: RDT UDP port.
        counts_per_force: Counts per N, None where the file does not give it (the bridge then
            needs the box's own calibration page).
        counts_per_torque: Counts per N m, likewise.
        rdt_rate_hz: The box's RDT output rate (Hz), likewise.
        source: The file these come from.
    """

    port: int
    counts_per_force: float | None = None
    counts_per_torque: float | None = None
    rdt_rate_hz: float | None = None
    source: str = ''


def robot_folder(robot_name: str) -> Path:
    """The folder of robot ``robot_name`` (uvms_description's robots/<name>/).

    Raises:
        HardwareConfigError: No such robot.
    """
    try:
        return robot_files(robot_name).directory
    except RobotFolderError as exc:
        raise HardwareConfigError(str(exc)) from exc


def hardware_section(robot_name: str, section: str) -> tuple[Path, Mapping[str, Any]]:
    """The ``section`` mapping of the robot's ``hardware.yaml`` and the file's path.

    Raises:
        HardwareConfigError: The robot, the file or the section is missing or malformed.
    """
    path = robot_folder(robot_name) / HARDWARE_FILE
    try:
        tree = yaml.safe_load(path.read_text(encoding='utf-8'))
    except OSError as exc:
        msg = f'{path}: robot {robot_name!r} has no readable {HARDWARE_FILE}: {exc.strerror}'
        raise HardwareConfigError(msg) from exc
    except yaml.YAMLError as exc:
        raise HardwareConfigError(f'{path}: malformed YAML: {exc}') from exc
    if not isinstance(tree, Mapping) or not isinstance(tree.get(section), Mapping):
        raise HardwareConfigError(f'{path}: no {section!r} section')
    return path, tree[section]


def urdf_joint_limits(robot_name: str) -> dict[str, tuple[float, float, float, float]]:
    """{joint: (lower, upper, velocity, effort)} of the URDF's revolute and prismatic joints.

    Raises:
        HardwareConfigError: The URDF cannot be read.
    """
    try:
        root = ET.fromstring(urdf_text(robot_files(robot_name).urdf))
    except (RobotFolderError, ET.ParseError) as exc:
        raise HardwareConfigError(f'robot {robot_name!r}: URDF: {exc}') from exc
    limits = {}
    for joint in root.iter('joint'):
        limit = joint.find('limit')
        if joint.get('type') in ('revolute', 'prismatic') and limit is not None:
            limits[str(joint.get('name'))] = (
                float(limit.get('lower', 0.0)), float(limit.get('upper', 0.0)),
                float(limit.get('velocity', 0.0)), float(limit.get('effort', 0.0)))
    return limits


def urdf_arm_joints(robot_name: str) -> tuple[str, ...]:
    """The URDF's arm joints, base to tip, as the model reads them (uvms_model.description).

    Raises:
        HardwareConfigError: The description cannot be read.
    """
    try:
        files = robot_files(robot_name)
        return load_description(files.urdf, files.hydrodynamics).joint_names
    except (RobotFolderError, DescriptionError) as exc:
        raise HardwareConfigError(f'robot {robot_name!r}: {exc}') from exc


def _number(path: Path, where: str, item: Mapping[str, Any], key: str) -> float:
    value = item.get(key)
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise HardwareConfigError(f'{path}: {where}.{key} = {value!r}: expected a number')
    return float(value)


def load_alpha5(robot_name: str, jaw_joint: str | None = '') -> Alpha5Hardware:
    """The Alpha 5 drives of ``robot_name``; the jaw is driven only when named ``jaw_joint``.

    ``jaw_joint`` None: the name the hardware file gives the jaws (``alpha5.jaw.joint_name``),
    driven when it gives one; '' (the default): the jaws are not driven (the plant's joints
    only, as the twin stand's plant and the hardware check take them).

    Raises:
        HardwareConfigError: A missing section or key, or a joint of ``hardware.yaml`` that
            the URDF does not have (the message names the file and the key).
    """
    path, section = hardware_section(robot_name, 'alpha5')
    urdf_limits = urdf_joint_limits(robot_name)
    joints = section.get('joints')
    if not isinstance(joints, Mapping) or not joints:
        raise HardwareConfigError(f'{path}: alpha5.joints: expected a mapping joint -> drive')
    arm_joints = urdf_arm_joints(robot_name)
    if tuple(joints) != arm_joints:
        raise HardwareConfigError(f'{path}: alpha5.joints {list(joints)}: expected the URDF arm '
                                  f'joints, base to wrist: {list(arm_joints)}')
    drives = []
    for name, item in joints.items():
        where = f'alpha5.joints.{name}'
        if name not in urdf_limits:
            raise HardwareConfigError(f'{path}: {where}: the URDF has no such moving joint')
        lower, upper, velocity, _ = urdf_limits[name]
        per_ma = (_number(path, where, item, 'kt_n_m_per_a') * _number(
            path, where, item, 'gear_ratio') * _number(path, where, item, 'efficiency')
            / _MA_PER_A)
        drives.append(Drive(str(name), int(_number(path, where, item, 'device_id')),
                            str(item.get('axis', '?')), (lower, upper), velocity,
                            _number(path, where, item, 'current_limit_ma'), per_ma))
    item = section.get('jaw')
    named = str(item.get('joint_name') or '') if isinstance(item, Mapping) else ''
    if jaw_joint is None:
        jaw_joint = named
    jaw_device = None
    if isinstance(item, Mapping) or jaw_joint:
        jaw_device = _jaw_drive(path, item, jaw_joint or named or 'jaw')
    jaw = jaw_device if jaw_joint else None
    return Alpha5Hardware(tuple(drives), jaw, int(section.get('udp_port', 6789)),
                          int(section.get('serial_baud', 115200)), jaw_device)


def _jaw_drive(path: Path, item: object, joint_name: str) -> Drive:
    """The jaws' drive of the ``alpha5.jaw`` section, as joint ``joint_name`` (m, m/s).

    Raises:
        HardwareConfigError: No such section, or a key missing or malformed.
    """
    if not isinstance(item, Mapping):
        raise HardwareConfigError(f'{path}: no alpha5.jaw section for jaw {joint_name!r}')
    limits = item.get('position_limits_m')
    if not (isinstance(limits, list) and len(limits) == 2):
        raise HardwareConfigError(f'{path}: alpha5.jaw.position_limits_m: expected [lo, hi]')
    return Drive(joint_name, int(_number(path, 'alpha5.jaw', item, 'device_id')),
                 str(item.get('axis', 'A')), (float(limits[0]), float(limits[1])),
                 _number(path, 'alpha5.jaw', item, 'velocity_limit_m_s'),
                 _number(path, 'alpha5.jaw', item, 'current_limit_ma'), 0.0)


def load_netft(robot_name: str) -> NetFtHardware:
    """The Net F/T section of ``robot_name``'s hardware file (what it does not give is None).

    Raises:
        HardwareConfigError: See `hardware_section`; a calibration or rate given that is not a
            positive number.
    """
    path, section = hardware_section(robot_name, 'netft')

    def positive(key: str) -> float | None:
        if section.get(key) is None:
            return None
        value = _number(path, 'netft', section, key)
        if value <= 0.0:
            raise HardwareConfigError(f'{path}: netft.{key} = {value}: must be > 0')
        return value

    return NetFtHardware(int(section.get('port', 49152)), positive('counts_per_force'),
                         positive('counts_per_torque'), positive('rdt_rate_hz'), str(path))
