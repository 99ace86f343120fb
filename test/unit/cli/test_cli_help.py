"""``uvms --help`` and ``uvms launch --help`` say what a launch does and when it ends."""

from __future__ import annotations

import re

import pytest
from uvms_bringup.launch_helpers import graph_nodes

from uvms_cli import cli


def _help(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    with pytest.raises(SystemExit) as done:
        cli.build_parser().parse_args(argv)
    assert done.value.code == 0
    return ' '.join(capsys.readouterr().out.split())


def test_top_level_help_says_launch_ends_at_the_scenario_duration(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The launch line of ``uvms --help`` names duration_s, not "until Ctrl-C"."""
    text = _help(['--help'], capsys)
    launch = re.search(r'launch (.*?) replay ', text)
    assert launch is not None
    assert 'Ctrl-C' not in launch.group(1)
    assert 'duration_s' in launch.group(1)


@pytest.mark.parametrize('command', ['launch', 'run'])
def test_help_lists_every_node_the_graph_can_start(
    command: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """Each node of the fullest graph (mission, live view, recorder) is named in the help."""
    text = _help([command, '--help'], capsys)
    for spec in graph_nodes(record=True, foxglove=True, mission=True):
        assert spec.name in text, spec.name


def test_launch_help_documents_every_exit_status(capsys: pytest.CaptureFixture[str]) -> None:
    """0, 1, 2, 3 (a failed mission, distinct from a node that failed) and 130 are explained."""
    text = _help(['launch', '--help'], capsys)
    statuses = re.search(r'exit status: (.*)', text)
    assert statuses is not None
    for status, meaning in [('0', 'reached the duration'), ('1', 'a node failed'),
                            ('2', 'bad usage'), ('3', 'mission failed'), ('130', 'Ctrl-C')]:
        assert re.search(rf'(^|; ){status} [^;]*{meaning}', statuses.group(1)), (status, text)
