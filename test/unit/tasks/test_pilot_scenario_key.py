"""A scenario's pilot: key becomes the controller's pilot.script; a mission task's send_at_s."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from uvms_control.core.pilot.script import load_script_text
from uvms_scenarios.scenario import ScenarioError, load_scenario
from uvms_tasks.task_file import parse_mission

SESSION = Path(__file__).resolve().parents[3] / 'config' / 'pilot' / 'press_100n_session.yaml'
HEAD = 'name: s\ndescription: d\nduration_s: 2.0\n'


def test_the_shipped_session_plays_its_commands_through_the_controller() -> None:
    """Its pilot: list is the controller's pilot.script; the task waits for its send time."""
    scenario = load_scenario(SESSION)
    script = load_script_text(str(scenario.overrides['controller']['pilot.script']))
    assert [c.at_s for c in script] == [1.0, 7.0, 15.0, 22.5]
    assert script[2].ee == (0.0, 0.0, 0.025)
    assert scenario.mission[0].send_at_s == 18.0


def test_a_pilot_file_next_to_the_scenario_is_read(tmp_path: Path) -> None:
    """pilot: NAME reads the list from a file beside the scenario."""
    (tmp_path / 'moves.yaml').write_text('- {at_s: 0.5, for_s: 1.0, jaw: -0.01}\n')
    path = tmp_path / 's.yaml'
    path.write_text(HEAD + 'pilot: moves.yaml\n')
    script = load_script_text(str(load_scenario(path).overrides['controller']['pilot.script']))
    assert script[0].jaw == -0.01


@pytest.mark.parametrize(('pilot', 'named'), [
    ('[{at_s: 1.0, for_s: 1.0, vehicle: [1, 2]}]', 'pilot[0].vehicle'),
    ('missing.yaml', 'a readable YAML pilot script'),
    ('{at_s: 1}', 'a list of timed commands'),
])
def test_a_wrong_pilot_key_is_named_before_anything_runs(tmp_path: Path, pilot: str,
                                                         named: str) -> None:
    """The file, the key and the entry are named."""
    path = tmp_path / 's.yaml'
    path.write_text(HEAD + f'pilot: {pilot}\n')
    with pytest.raises(ScenarioError, match=named.replace('[', r'\[')):
        load_scenario(path)


def test_pilot_and_controller_pilot_script_both_set_is_refused(tmp_path: Path) -> None:
    """One place sets the script."""
    path = tmp_path / 's.yaml'
    path.write_text(HEAD + "pilot: [{at_s: 1.0, hold: true}]\ncontroller:\n  pilot:\n"
                    "    script: ''\n")
    with pytest.raises(ScenarioError, match='keep one'):
        load_scenario(path)


def test_a_scenario_without_pilot_sets_no_script() -> None:
    """Unused, the pilot adds nothing to the controller's parameters."""
    idle = SESSION.parents[1] / 'scenarios' / 'idle_wall.yaml'
    assert 'pilot.script' not in load_scenario(idle).overrides.get('controller', {})


def test_send_at_s_is_read_and_checked() -> None:
    """A number >= 0; absent: None (sent at once, as before)."""
    task = yaml.safe_load('{path: [[0, 0, 0], [0.1, 0, 0]], time_from_start_s: [0, 1], '
                          'normal: [1, 0, 0]}')
    assert parse_mission([task], 'm')[0].send_at_s is None
    assert parse_mission([{**task, 'send_at_s': 3}], 'm')[0].send_at_s == 3.0
    with pytest.raises(ValueError, match='send_at_s'):
        parse_mission([{**task, 'send_at_s': -1}], 'm')
