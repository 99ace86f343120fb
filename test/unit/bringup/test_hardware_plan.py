"""Hardware files: which bridges a launch starts, where they connect, and what the twins change."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest
from uvms_bringup.hardware_plan import (
    BRIDGES,
    HardwareFileError,
    hardware_file_path,
    hardware_nodes,
    hardware_parameters,
    hardware_scenario,
    load_hardware_plan,
)
from uvms_bringup.launch_helpers import graph_nodes
from uvms_scenarios.scenario import load_scenario

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
    with pytest.raises(HardwareFileError, match='shipped: bluerov2_pool, twin, twin_alpha5_bus'):
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


def test_with_twins_physics_waits_for_every_bridge_to_drive_its_device() -> None:
    """Physics holds until the bridges too are active: else the arm falls, the vehicle drifts.

    Before the bridges drive them, the arm twin makes no torque and the estimator has no IMU.
    """
    plan = load_hardware_plan(hardware_file_path('twin', CONFIG))
    nodes = hardware_nodes(graph_nodes(record=True, mission=True, estimator=True), plan)
    waits_for = hardware_parameters(nodes, plan)['simulator']['startup.nodes']
    assert set(waits_for) == {'controller', 'thruster_allocator', *BRIDGES}


def test_with_twins_every_node_but_the_simulator_runs_on_its_clock() -> None:
    """The simulator is the clock: it alone keeps wall time; the bridges stamp with /clock."""
    plan = replace(load_hardware_plan(hardware_file_path('twin', CONFIG)),
                   twins_in_simulator=False)
    nodes = hardware_nodes(graph_nodes(record=True, mission=True, estimator=True), plan)
    values = hardware_parameters(nodes, plan)
    assert 'use_sim_time' not in values['simulator']
    assert all(values[name]['use_sim_time'] for name in (*BRIDGES, 'hardware_twins'))
    names = [spec.name for spec in nodes]
    assert names[:6] == ['simulator', 'hardware_twins', *BRIDGES]


def test_by_default_the_twins_serve_in_the_simulators_process_where_the_bridges_connect(
        ) -> None:
    """--hardware twin: no twins process; the simulator gets each bridge's connection."""
    plan = load_hardware_plan(hardware_file_path('twin', CONFIG))
    assert plan.twins_in_simulator
    nodes = hardware_nodes(graph_nodes(record=True, mission=True, estimator=True), plan)
    assert [spec.name for spec in nodes][:5] == ['simulator', *BRIDGES]
    values = hardware_parameters(nodes, plan)
    assert 'hardware_twins' not in values
    assert values['simulator']['twins.alpha5_bridge.connection'] == (
        plan.bridges['alpha5_bridge']['connection'])
    assert values['simulator']['startup.nodes'][-4:] == list(BRIDGES)


def test_on_the_robot_the_bridges_replace_the_simulator_and_nothing_waits_for_clock(
        tmp_path: Path) -> None:
    """twins: false: no simulator, so no /clock: every node on wall time."""
    path = tmp_path / 'robot.yaml'
    path.write_text('twins: false\nbridges: {alpha5_bridge: {connection: "udp:10.0.0.2:6789"}}')
    plan = load_hardware_plan(path)
    nodes = hardware_nodes(graph_nodes(record=True, estimator=True), plan)
    assert [spec.name for spec in nodes][:2] == ['alpha5_bridge', 'estimator']
    values = hardware_parameters(nodes, plan)
    assert not any(v.get('use_sim_time') for v in values.values())


def test_the_scenario_on_hardware_runs_the_controller_on_the_estimate() -> None:
    """A robot has no ground truth; the propellers do the thruster dynamics."""
    scenario = load_scenario(CONFIG / 'scenarios' / 'bluerov2_alpha5_contact.yaml')
    plan = load_hardware_plan(hardware_file_path('twin', CONFIG))
    changed = hardware_scenario(scenario, plan)
    assert changed.overrides['controller']['state_source'] == 'estimate'
    assert changed.overrides['thruster_allocator']['thruster_output'] == 'desired'
    assert changed.overrides['simulator']['navigation.enabled'] is True
    assert changed.overrides['simulator']['world.seabed_depth_m'] == 2.0
    assert changed.overrides['simulator']['devices.ideal'] is True  # the twins keep the timing
    assert 'state_source' not in scenario.overrides.get('controller', {})


def test_twin_settings_reach_the_stand_in_the_simulator_or_in_its_own_node() -> None:
    """twins: {alpha5_bus: true}: the stand's setting, where the twins serve; the bridge's own.

    The shipped ``twin_alpha5_bus`` file keeps the arm's RS-485 line in the twin and has the
    bridge schedule it (docs/hardware.md, "The Alpha 5 bus").
    """
    plan = load_hardware_plan(hardware_file_path('twin_alpha5_bus', CONFIG))
    assert plan.twins and plan.twin_settings == {'alpha5_bus': True}
    assert plan.bridges['alpha5_bridge']['bus_schedule'] is True
    nodes = hardware_nodes(graph_nodes(record=True, mission=True, estimator=True), plan)
    assert hardware_parameters(nodes, plan)['simulator']['twins.alpha5_bus'] is True
    apart = replace(plan, twins_in_simulator=False)
    nodes = hardware_nodes(graph_nodes(record=True, mission=True, estimator=True), apart)
    assert hardware_parameters(nodes, apart)['hardware_twins']['alpha5_bus'] is True

