"""A pilot script: timed commands parsed with the entry and key named, played each step."""

from __future__ import annotations

import pytest
from uvms_control.core.errors import ControlParameterError
from uvms_control.core.pilot.script import ScriptPlayer, load_script_text

TEXT = """
- {at_s: 1.0, for_s: 2.0, vehicle: [0.2, 0, 0, 0, 0, 0]}
- {at_s: 0.5, for_s: 1.0, ee: [0, 0, 0.02], frame: map_ned}
- {at_s: 4.0, hold: true}
"""


def test_a_script_is_sorted_by_its_start_times() -> None:
    """Entries in any order; the frame and vectors kept."""
    commands = load_script_text(TEXT)
    assert [c.at_s for c in commands] == [0.5, 1.0, 4.0]
    assert commands[0].frame == 'map_ned'
    assert commands[1].vehicle == (0.2, 0.0, 0.0, 0.0, 0.0, 0.0)


def test_commands_are_sent_while_active_and_a_hold_once() -> None:
    """Each step sends what is active; a hold goes out at its time, once."""
    player = ScriptPlayer(load_script_text(TEXT))
    assert player.due(0.0) == []
    assert len(player.due(1.2)) == 2
    assert player.due(3.0) == []
    assert player.due(4.0)[0].hold
    assert player.due(4.002) == []


@pytest.mark.parametrize(('text', 'named'), [
    ('- {at_s: 1.0, for_s: 1.0, vehicle: [0.1, 0]}', 'pilot.script[0].vehicle'),
    ('- {at_s: -1.0, hold: true}', 'pilot.script[0].at_s'),
    ('- {at_s: 1.0, speed: 3}', 'pilot.script[0]'),
    ('- {at_s: 1.0, for_s: 1.0}', 'pilot.script[0]'),
    ('{at_s: 1.0}', 'pilot.script'),
    ('[unclosed', 'pilot.script'),
])
def test_a_wrong_entry_is_named(text: str, named: str) -> None:
    """The error names the entry and key."""
    with pytest.raises(ControlParameterError, match=named.replace('[', r'\[')):
        load_script_text(text)


def test_an_empty_script_plays_nothing() -> None:
    """'' is no script."""
    assert load_script_text('') == ()
