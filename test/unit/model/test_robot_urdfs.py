"""Every shipped robot's URDF read by a plain XML parser: masses, joint count, one chain."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import pytest

from uvms_description.robots import robot_files, robot_names, urdf_text
from uvms_model import load_description

ROBOTS = robot_names()


def _tree(robot: str) -> ET.Element:
    """The robot's URDF after xacro expansion, parsed by xml.etree."""
    return ET.fromstring(urdf_text(robot_files(robot).urdf))


@pytest.mark.parametrize('robot', ROBOTS)
def test_every_mass_is_positive(robot: str) -> None:
    """Each <inertial><mass value> is a positive number; the root has one."""
    masses = {link.get('name'): float(mass.get('value', 'nan'))
              for link in _tree(robot).iter('link')
              if (mass := link.find('inertial/mass')) is not None}
    assert 'base_link_frd' in masses
    assert all(value > 0.0 for value in masses.values()), masses


@pytest.mark.parametrize('robot', ROBOTS)
def test_one_chain_of_at_least_three_revolute_joints_from_base_link_frd_to_ee_link(
    robot: str,
) -> None:
    """base_link_frd is the only root; the path to ee_link holds every movable joint, >= 3."""
    root = _tree(robot)
    links = {link.get('name') for link in root.iter('link')}
    joints = list(root.iter('joint'))
    parent_of = {j.find('child').get('link'): j for j in joints}  # type: ignore[union-attr]
    assert [name for name in links if name not in parent_of] == ['base_link_frd']
    assert {'ee_link', 'ft_sensor_link'} <= links
    path, link = [], 'ee_link'
    while link != 'base_link_frd':
        joint = parent_of[link]
        path.append(joint)
        link = joint.find('parent').get('link')  # type: ignore[union-attr,assignment]
    revolute = [j.get('name') for j in reversed(path) if j.get('type') == 'revolute']
    movable = [j.get('name') for j in joints if j.get('type') != 'fixed']
    assert len(revolute) >= 3
    assert sorted(movable) == sorted(revolute), 'a movable joint off the chain (a branch)'
    assert tuple(revolute) == load_description(robot_files(robot).urdf,
                                               robot_files(robot).hydrodynamics).joint_names
