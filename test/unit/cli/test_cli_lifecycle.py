"""``uvms lifecycle NODE ACTION``: its arguments, and a call on a graph that is not there."""

from __future__ import annotations

import pytest

from uvms_cli import cli, lifecycle


def test_lifecycle_is_a_subcommand_of_uvms(capsys: pytest.CaptureFixture[str]) -> None:
    """``uvms --help`` lists it, with reset clearing the safe hold."""
    with pytest.raises(SystemExit):
        cli.build_parser().parse_args(['--help'])
    text = ' '.join(capsys.readouterr().out.split())
    assert 'lifecycle' in text and 'clears a safe hold' in text


def test_unknown_action_is_bad_usage(capsys: pytest.CaptureFixture[str]) -> None:
    """An action that is no transition exits 2 and lists the valid ones."""
    assert cli.main(['lifecycle', 'controller', 'restart']) == 2
    err = capsys.readouterr().err
    for action in lifecycle.ACTIONS:
        assert action in err


def test_node_that_does_not_answer_is_a_failure_naming_its_service(
        capsys: pytest.CaptureFixture[str]) -> None:
    """No graph on this domain: exit 1 naming the get_state service it waited for."""
    assert lifecycle.main(['nosuch', 'get', '--timeout', '0.5']) == 1
    assert '/uvms/nosuch/get_state did not appear within 0.5 s' in capsys.readouterr().err
