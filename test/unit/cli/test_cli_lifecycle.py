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


def _managed_node_names() -> set[str]:
    """Names of the nodes whose classes are lifecycle nodes, read from the sources (ast)."""
    import ast
    from pathlib import Path

    root = Path(__file__).resolve().parents[3] / 'src'
    bases = {'LifecycleNode', 'BridgeNode'}
    names = set()
    for path in root.glob('*/*/*_node.py'):
        for cls in ast.walk(ast.parse(path.read_text(encoding='utf-8'))):
            if not isinstance(cls, ast.ClassDef) or not any(
                    isinstance(base, ast.Name) and base.id in bases for base in cls.bases):
                continue
            for call in ast.walk(cls):
                if (isinstance(call, ast.Call) and isinstance(call.func, ast.Attribute)
                        and call.func.attr == '__init__' and call.args
                        and isinstance(call.args[0], ast.Constant)):
                    names.add(str(call.args[0].value))
    return names


def test_help_lists_every_managed_node(capsys: pytest.CaptureFixture[str]) -> None:
    """The bridges and the estimator are managed too: ``--help`` names each of them."""
    managed = _managed_node_names()
    assert {'controller', 'thruster_allocator', 'alpha5_bridge'} <= managed
    assert lifecycle.main(['--help']) == 0
    text = ' '.join(capsys.readouterr().out.split())
    for name in managed:
        assert name in text
