"""Hardware constants of bluerov2_alpha5: the arm's drives, URDF limits, torque <-> current."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from uvms_hardware.hardware_config import HardwareConfigError, load_alpha5, load_netft

from uvms_description.robots import robot_files

ROBOT = 'bluerov2_alpha5'


def test_urdf_arm_joints_map_to_devices_e_d_c_b() -> None:
    """joint_1..joint_4 (base to wrist) are devices 0x05..0x02; the jaw is not driven."""
    arm = load_alpha5(ROBOT)
    assert [(d.joint_name, d.device_id, d.axis) for d in arm.joints] == [
        ('joint_1', 5, 'E'), ('joint_2', 4, 'D'), ('joint_3', 3, 'C'), ('joint_4', 2, 'B')]
    assert arm.jaw is None


def test_limits_are_the_urdfs() -> None:
    """joint_2 is -3.49..3.49 rad at 0.5 rad/s, as robot.urdf says."""
    drive = load_alpha5(ROBOT).joints[1]
    assert drive.position_limits == (-3.49, 3.49) and drive.velocity_limit == 0.5


def test_jaw_is_driven_when_named_with_limits_in_metres() -> None:
    """A named jaw is device 0x01 with 0-0.015 m."""
    jaw = load_alpha5(ROBOT, jaw_joint='jaw').jaw
    assert jaw is not None and jaw.device_id == 1 and jaw.position_limits == (0.0, 0.015)


def test_torque_to_current_uses_kt_gear_and_efficiency() -> None:
    """1 N m at joint_1 is 1 / (0.0134 * 1754.4 * 0.86) A; joint_4 uses 0.0271, 340.4, 77 %."""
    base, wrist = load_alpha5(ROBOT).joints[0], load_alpha5(ROBOT).joints[3]
    assert base.current_ma(1.0) == pytest.approx(1000.0 / (0.0134 * 1754.4 * 0.86))
    assert wrist.current_ma(1.0) == pytest.approx(1000.0 / (0.0271 * 340.4 * 0.77))
    assert base.torque_n_m(base.current_ma(2.5)) == pytest.approx(2.5)


def test_current_is_clamped_at_the_limit() -> None:
    """9 N m at joint_2 would need 445 mA; its limit is 400 mA."""
    assert load_alpha5(ROBOT).joints[1].current_ma(-9.0) == -400.0


def test_netft_defaults_are_a_million_counts() -> None:
    """The default calibration is 1e6 counts per N and per N m on port 49152."""
    config = load_netft(ROBOT)
    assert (config.port, config.counts_per_force, config.counts_per_torque) == (
        49152, 1e6, 1e6)


def test_robot_without_hardware_file_is_named() -> None:
    """The paper robot has no hardware.yaml: the error names the file."""
    with pytest.raises(HardwareConfigError, match=r'hardware\.yaml'):
        load_alpha5('paper_uvms')


def test_hardware_joints_must_be_the_urdf_arm_joints(tmp_path: Path) -> None:
    """A hardware.yaml naming joint_2 before joint_1 is refused, naming the URDF's order."""
    folder = tmp_path / 'swapped'
    shutil.copytree(robot_files(ROBOT).directory, folder)
    text = (folder / 'hardware.yaml').read_text(encoding='utf-8')
    lines = text.splitlines(keepends=True)
    first = next(i for i, line in enumerate(lines) if line.strip().startswith('joint_1:'))
    lines[first], lines[first + 1] = lines[first + 1], lines[first]
    (folder / 'hardware.yaml').write_text(''.join(lines), encoding='utf-8')
    with pytest.raises(HardwareConfigError, match='base to wrist'):
        load_alpha5(str(folder))
