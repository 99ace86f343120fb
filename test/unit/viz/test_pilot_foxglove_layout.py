"""The shipped layout's Teleop panels: on the pilot topics, faster than the deadman, in limits."""

from __future__ import annotations

import json
from typing import Any

import pytest
from uvms_pilot.limits import pilot_limits
from uvms_viz.foxglove_client_publish import ACCEPTED

import uvms_description

LAYOUT = json.loads(uvms_description.foxglove_layout_path().read_text(encoding='utf-8'))
TELEOP = {panel_id: config for panel_id, config in LAYOUT['configById'].items()
          if panel_id.startswith('Teleop!')}
BUTTONS = ('upButton', 'downButton', 'leftButton', 'rightButton')
#: The controller's deadman (s): no pilot message for this long means zero, then hold.
DEADMAN_S = 0.3


def panels_in_tree(node: Any) -> set[str]:
    """The panel ids the layout tree places."""
    if isinstance(node, str):
        return {node}
    return panels_in_tree(node['first']) | panels_in_tree(node['second'])


def test_vehicle_and_arm_teleop_panels_are_placed_on_pilot_topics() -> None:
    """One Teleop panel drives the vehicle, one the arm; both placed, both taken by the server."""
    topics = {config['topic'] for config in TELEOP.values()}
    assert topics == {'/uvms/pilot/vehicle_twist', '/uvms/pilot/ee_twist'}
    assert {topic.removeprefix('/uvms/') for topic in topics} <= set(ACCEPTED)
    assert set(TELEOP) <= panels_in_tree(LAYOUT['layout'])


@pytest.mark.parametrize('panel_id', sorted(TELEOP))
def test_teleop_publishes_faster_than_the_deadman(panel_id: str) -> None:
    """Below 1/deadman the controller would stop between two messages of a held button."""
    assert TELEOP[panel_id]['publishRate'] > 2.0 / DEADMAN_S


@pytest.mark.parametrize('robot', ['paper_uvms', 'bluerov2_alpha5'])
@pytest.mark.parametrize('panel_id', sorted(TELEOP))
def test_teleop_buttons_stay_within_every_robots_pilot_limits(panel_id: str, robot: str) -> None:
    """No button asks for more than a shipped robot's pilot limit (the controller would clip)."""
    limits = pilot_limits(robot)
    config = TELEOP[panel_id]
    vehicle = config['topic'].endswith('vehicle_twist')
    allowed = ({'linear-x': limits.vehicle_m_s[0], 'linear-y': limits.vehicle_m_s[1],
                'linear-z': limits.vehicle_m_s[2], 'angular-z': limits.yaw_rad_s} if vehicle
               else {'linear-x': limits.ee_m_s[0], 'linear-y': limits.ee_m_s[1],
                     'linear-z': limits.ee_m_s[2]})
    for button in BUTTONS:
        field, value = config[button]['field'], config[button]['value']
        assert field in allowed, f'{panel_id}.{button} drives {field}'
        assert 0.0 < abs(value) <= allowed[field], f'{panel_id}.{button}: {value} on {field}'


def test_vehicle_left_turns_left_in_base_link_frd() -> None:
    """Yaw is about z down: the left button is a negative rate, the right one positive."""
    config = TELEOP['Teleop!vehicle']
    assert config['leftButton'] == {'field': 'angular-z', 'value': -abs(
        config['rightButton']['value'])}
    assert config['upButton']['field'] == 'linear-x' and config['upButton']['value'] > 0
