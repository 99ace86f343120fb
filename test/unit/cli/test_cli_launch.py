"""Tests of `uvms launch`'s options (uvms_cli.cli): which duration the launch is given."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from uvms_bringup.launch_helpers import config_dir

from uvms_bringup import launcher
from uvms_cli import cli


@pytest.fixture
def launched(monkeypatch: pytest.MonkeyPatch) -> dict[str, Any]:
    """What `uvms launch` hands to ``launch_graph`` (which starts nothing here)."""
    calls: dict[str, Any] = {}

    def fake_launch_graph(scenario: Any, mode: str, **kwargs: Any) -> int:
        calls.update(kwargs, scenario=scenario, mode=mode)
        return 0

    monkeypatch.setattr(launcher, 'launch_graph', fake_launch_graph)
    return calls


@pytest.mark.parametrize(
    ('argv', 'duration_s'),
    [
        (['free_motion'], 20.0),
        (['free_motion', '--duration', '3'], 3.0),
        (['free_motion', '--duration', '0'], None),
        ([], None),
    ],
    ids=['scenario-duration', 'option', 'zero-runs-on', 'no-scenario'],
)
def test_launch_honours_the_scenario_duration_unless_told_to_run_on(
    launched: dict[str, Any], argv: list[str], duration_s: float | None
) -> None:
    """The scenario's duration_s ends the launch; --duration replaces it; 0 runs on."""
    assert cli.main(['launch', *argv]) == 0
    assert launched['duration_s'] == duration_s
    if launched['scenario'] is not None and duration_s:
        assert launched['scenario'].duration_s == duration_s


def test_launch_refuses_a_negative_duration(
    launched: dict[str, Any], capsys: pytest.CaptureFixture[str]
) -> None:
    """A negative --duration is a usage error (exit 2) and launches nothing."""
    assert cli.main(['launch', 'free_motion', '--duration', '-1']) == 2
    assert not launched
    assert '--duration' in capsys.readouterr().err


@pytest.mark.parametrize('command', ['run', 'launch'])
def test_unknown_scenario_name_lists_the_scenarios_and_is_bad_usage(
    launched: dict[str, Any], command: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """`uvms launch nosuch_scenario`: exit 2, the scenarios there are named."""
    assert cli.main([command, 'nosuch_scenario']) == 2
    err = capsys.readouterr().err
    assert "no scenario 'nosuch_scenario'" in err
    assert 'case1_ke1e4' in err and 'idle_wall' in err


@pytest.mark.parametrize('command', ['run', 'launch'])
def test_unknown_robot_is_bad_usage_before_anything_starts(
    launched: dict[str, Any], command: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """`--robot nosuch`: exit 2 (not 1, "a node failed"), the robots listed, nothing launched."""
    assert cli.main([command, 'free_motion', '--robot', 'nosuch']) == 2
    assert "unknown robot 'nosuch'" in capsys.readouterr().err
    assert launched == {}


def test_negative_launch_duration_says_zero_is_valid(capsys: pytest.CaptureFixture[str]) -> None:
    """`--duration -5`: the message says >= 0 (0 runs until Ctrl-C), not > 0."""
    assert cli.main(['launch', 'free_motion', '--duration', '-5']) == 2
    assert 'expected a number of seconds >= 0 (0: run until Ctrl-C)' in capsys.readouterr().err


def test_robot_help_says_a_path_works(capsys: pytest.CaptureFixture[str]) -> None:
    """`uvms launch --help`: --robot takes a name or a path to a robot folder."""
    with pytest.raises(SystemExit):
        cli.build_parser().parse_args(['launch', '--help'])
    assert 'or a path to a robot folder' in ' '.join(capsys.readouterr().out.split())


def test_top_level_help_gives_every_subcommands_exit_statuses(
    capsys: pytest.CaptureFixture[str]
) -> None:
    """`uvms --help`: 0, 1, 2, 3 and 130 for every subcommand."""
    with pytest.raises(SystemExit):
        cli.build_parser().parse_args(['--help'])
    text = ' '.join(capsys.readouterr().out.split())
    assert 'exit status, every subcommand: 0 success; 1' in text
    for status in ('2 bad usage', '3 uvms launch only', '130 interrupted'):
        assert status in text


def test_scenario_key_typo_is_the_only_line_of_uvms_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A mistyped override with a short --duration: the key's error, no duration warning."""
    scenario = Path(__file__).resolve().parents[3] / 'config' / 'scenarios' / 'case1_ke1e4.yaml'
    typo = tmp_path / 'typo.yaml'
    typo.write_text(scenario.read_text().replace('stiffness_n_m', 'stifness_n_m', 1))
    assert cli.main(['run', str(typo), '--duration', '0.1']) == 2
    err = capsys.readouterr().err
    assert 'stifness_n_m' in err
    assert 'warning' not in err


def test_real_time_factor_reaches_the_launch_and_zero_is_refused(
    launched: dict[str, Any], capsys: pytest.CaptureFixture[str]
) -> None:
    """--real-time-factor 0.5 is handed on; 0 is bad usage naming the option and its range."""
    assert cli.main(['launch', 'free_motion', '--real-time-factor', '0.5']) == 0
    assert launched['real_time_factor'] == 0.5
    launched.clear()
    assert cli.main(['launch', 'free_motion', '--real-time-factor', '0']) == 2
    assert not launched
    err = capsys.readouterr().err
    assert '--real-time-factor' in err and '0.01 to 10' in err


@pytest.mark.parametrize('with_file', [False, True], ids=['no-hardware', 'no-twins'])
def test_twins_apart_without_twins_is_refused_naming_the_flag(
    launched: dict[str, Any], capsys: pytest.CaptureFixture[str], tmp_path: Path,
    with_file: bool
) -> None:
    """--twins-apart with no twins to run apart: exit 2 naming it, nothing launched."""
    hardware: list[str] = []
    if with_file:  # the shipped real-robot file, its one placeholder filled in
        pool = config_dir() / 'hardware' / 'bluerov2_pool.yaml'
        real = tmp_path / 'pool.yaml'
        real.write_text(pool.read_text().replace('SET-ME', '192.168.2.10'))
        hardware = ['--hardware', str(real)]
    assert cli.main(['launch', 'bluerov2_alpha5_contact', '--twins-apart', *hardware]) == 2
    assert not launched
    assert '--twins-apart needs --hardware twin' in capsys.readouterr().err


def test_twins_apart_with_the_twin_stand_runs_them_in_their_own_process(
    launched: dict[str, Any]
) -> None:
    """--hardware twin --twins-apart: the hardware plan says the twins are not in the simulator."""
    assert cli.main(['launch', 'bluerov2_alpha5_contact', '--hardware', 'twin',
                     '--twins-apart']) == 0
    assert launched['hardware'].twins and not launched['hardware'].twins_in_simulator


@pytest.mark.parametrize(('twins', 'said'), [
    ('{alpha5_buss: true}', 'twins.alpha5_buss: not a setting of the stand; known: '),
    ('{alpha5_bridge.connection: "udp:127.0.0.1:1"}', 'twins.alpha5_bridge.connection: not a'),
    ('{alpha5_bus: 1}', 'twins.alpha5_bus = 1: expected a bool'),
])
def test_a_twin_setting_the_stand_does_not_have_is_refused_naming_it(
    launched: dict[str, Any], capsys: pytest.CaptureFixture[str], tmp_path: Path,
    twins: str, said: str
) -> None:
    """A misspelt or mistyped ``twins:`` setting: exit 2 naming it, nothing launched.

    Unchecked, a ROS parameter of that name would be ignored and the stand run without it.
    """
    stand = tmp_path / 'stand.yaml'
    stand.write_text((config_dir() / 'hardware' / 'twin.yaml').read_text().replace(
        'twins: true', f'twins: {twins}'))
    assert cli.main(['launch', 'bluerov2_alpha5_contact', '--hardware', str(stand)]) == 2
    assert not launched
    assert said in capsys.readouterr().err


def test_twin_settings_reach_the_launch_checked(launched: dict[str, Any], tmp_path: Path
                                                ) -> None:
    """twins: {alpha5_bus: true, netft_rate_hz: 1000}: the launch gets them, 1000 as 1000.0."""
    stand = tmp_path / 'stand.yaml'
    stand.write_text((config_dir() / 'hardware' / 'twin.yaml').read_text().replace(
        'twins: true', 'twins: {alpha5_bus: true, netft_rate_hz: 1000}'))
    assert cli.main(['launch', 'bluerov2_alpha5_contact', '--hardware', str(stand)]) == 0
    assert launched['hardware'].twin_settings == {'alpha5_bus': True, 'netft_rate_hz': 1000.0}
