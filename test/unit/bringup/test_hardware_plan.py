"""Hardware files: which bridges a launch starts, where they connect, and what the twins change."""

from __future__ import annotations

from pathlib import Path

import pytest
from uvms_bringup.hardware_plan import (
    BRIDGES,
    HardwareFileError,
    hardware_file_path,
    load_hardware_plan,
)

CONFIG = Path(__file__).resolve().parents[3] / 'config'


def test_the_twin_file_names_every_bridge_on_loopback() -> None:
    """--hardware twin: the four bridges, each connecting to 127.0.0.1, twins on."""
    plan = load_hardware_plan(hardware_file_path('twin', CONFIG))
    assert plan.twins
    assert list(plan.bridges) == list(BRIDGES)
    assert all('127.0.0.1' in value for value in plan.twin_parameters().values())


def test_with_twins_the_simulator_device_topics_move_under_plant() -> None:
    """The bridges publish joint_states, wrench, imu, dvl, depth; the plant's go to /plant."""
    plan = load_hardware_plan(hardware_file_path('twin', CONFIG))
    remaps = dict(plan.simulator_remaps())
    assert remaps['joint_states'] == '/plant/joint_states'
    assert remaps['command/actuators'] == '/plant/command/actuators'
    assert 'odometry' not in remaps and 'contact' not in remaps  # ground truth stays


def test_the_pool_file_refuses_until_its_placeholder_is_set() -> None:
    """The shipped pool example names the one address the user must set."""
    with pytest.raises(HardwareFileError, match=r'bridges\.netft_bridge\.address'):
        load_hardware_plan(hardware_file_path('bluerov2_pool', CONFIG))


def test_an_unknown_file_lists_the_shipped_ones() -> None:
    """A typo in --hardware answers with the files there are."""
    with pytest.raises(HardwareFileError, match='shipped: bluerov2_pool, twin'):
        hardware_file_path('twins', CONFIG)


@pytest.mark.parametrize(('text', 'key'), [
    ('bridges: {dvl_bridge: {}}', 'bridges.dvl_bridge.address'),
    ('bridges: {sonar_bridge: {address: x}}', 'bridges.sonar_bridge'),
    ('twin: true\nbridges: {}', "unknown keys ['twin']"),
    ('twins: yes-please\nbridges: {}', 'twins'),
    ('bridges: {}', 'names no bridge'),
])
def test_a_bad_file_is_refused_naming_its_key(tmp_path: Path, text: str, key: str) -> None:
    """Each mistake is refused before anything starts, with the key named."""
    path = tmp_path / 'robot.yaml'
    path.write_text(text)
    with pytest.raises(HardwareFileError, match=key.replace('[', r'\[').replace('.', r'\.')):
        load_hardware_plan(path)
