"""Tests of `uvms launch`'s options (uvms_cli.cli): which duration the launch is given."""

from __future__ import annotations

from typing import Any

import pytest

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
