"""uvms run --pilot FILE: the file's commands become the controller's pilot.script."""

from __future__ import annotations

from pathlib import Path

import pytest
from uvms_control.core.pilot.script import load_script_text
from uvms_scenarios.pilot import with_pilot
from uvms_scenarios.scenario import ScenarioError, load_scenario

from uvms_cli import cli

IDLE = Path(__file__).resolve().parents[3] / 'config' / 'scenarios' / 'idle_wall.yaml'


def test_a_pilot_file_is_played_by_the_controller(tmp_path: Path) -> None:
    """The commands land in the controller's overrides; the rest of the scenario is kept."""
    moves = tmp_path / 'moves.yaml'
    moves.write_text('- {at_s: 1.0, for_s: 2.0, vehicle: [-0.1, 0, 0, 0, 0, 0]}\n')
    scenario = with_pilot(load_scenario(IDLE), moves)
    script = load_script_text(str(scenario.overrides['controller']['pilot.script']))
    assert script[0].vehicle == (-0.1, 0.0, 0.0, 0.0, 0.0, 0.0)
    assert scenario.overrides['simulator'] == load_scenario(IDLE).overrides['simulator']


def test_a_wrong_pilot_file_is_named(tmp_path: Path) -> None:
    """A missing file or a wrong entry stops the run before anything starts."""
    with pytest.raises(ScenarioError, match='--pilot'):
        with_pilot(load_scenario(IDLE), tmp_path / 'missing.yaml')


def test_uvms_run_takes_the_flag() -> None:
    """--pilot FILE is an option of uvms run."""
    args = cli.build_parser().parse_args(['run', 'idle_wall', '--pilot', 'moves.yaml'])
    assert args.pilot == 'moves.yaml'
