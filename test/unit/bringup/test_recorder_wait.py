"""What the launchers tell the simulator to wait for before its first state: the recorder."""

from __future__ import annotations

from pathlib import Path

import yaml
from uvms_bringup.launch_helpers import CONTROLLER, SIMULATOR, recorder_wait
from uvms_scenarios.scenario import Scenario, load_scenario
from uvms_sim.parameters import recorder_topics


def scenario_with(tmp_path: Path, recorder: dict[str, object] | None) -> Scenario:
    """A scenario file of the paper robot with ``recorder`` overrides."""
    data: dict[str, object] = {'name': 'rec', 'description': 'a recording', 'duration_s': 1.0}
    if recorder is not None:
        data['recorder'] = recorder
    path = tmp_path / 'rec.yaml'
    path.write_text(yaml.safe_dump(data))
    return load_scenario(path)


def test_the_simulator_waits_for_the_recorder_only_when_it_records(tmp_path: Path) -> None:
    """No recording or another node: nothing; a recording: the recorder, every state topic."""
    scenario = scenario_with(tmp_path, None)
    assert recorder_wait(SIMULATOR, False, scenario) == {}
    assert recorder_wait(CONTROLLER, True, scenario) == {}
    assert recorder_wait(SIMULATOR, True, scenario) == {'startup.recorder': 'recorder'}


def test_a_recorder_of_its_own_topics_gives_the_simulator_those(tmp_path: Path) -> None:
    """`recorder: {topics: [name:type, ...]}`: the names, for the simulator to wait on."""
    scenario = scenario_with(tmp_path, {'topics': ['/clock:rosgraph_msgs/msg/Clock',
                                                   'imu:sensor_msgs/msg/Imu']})
    assert recorder_wait(SIMULATOR, True, scenario) == {
        'startup.recorder': 'recorder', 'startup.recorder_topics': ['/clock', 'imu']}


def test_the_wildcard_is_every_state_topic() -> None:
    """['*'], the parameter's default: () for the settings, every state topic waited for."""
    assert recorder_topics(['*']) == ()
    assert recorder_topics(['joint_states']) == ('joint_states',)
