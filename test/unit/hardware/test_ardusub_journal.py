"""The journal of original device values (device_journal), as the ArduSub bridge uses it."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from uvms_hardware.device_journal import DeviceJournal, JournalError, journal_dir, journal_name


def test_what_is_recorded_reads_back_from_disk(tmp_path: Path) -> None:
    """Write then read through a fresh object: the same values, in a JSON file of its own."""
    DeviceJournal.for_device('ardusub', 'udpout:127.0.0.1:14550', str(tmp_path)).record(
        {'SERVO1_FUNCTION': 33.0, 'SERVO2_FUNCTION': 34.0})
    again = DeviceJournal.for_device('ardusub', 'udpout:127.0.0.1:14550', str(tmp_path))
    assert again.read() == {'SERVO1_FUNCTION': 33.0, 'SERVO2_FUNCTION': 34.0}
    assert json.loads(again.path.read_text())['values']['SERVO2_FUNCTION'] == 34.0
    assert not list(tmp_path.glob('*.tmp'))


def test_an_original_already_recorded_is_never_overwritten(tmp_path: Path) -> None:
    """A second record of the same name keeps the first (older) value: the true original."""
    journal = DeviceJournal(tmp_path / 'a.json')
    journal.record({'SERVO1_FUNCTION': 33.0})
    journal.record({'SERVO1_FUNCTION': 51.0, 'SERVO2_FUNCTION': 34.0})
    assert journal.read() == {'SERVO1_FUNCTION': 33.0, 'SERVO2_FUNCTION': 34.0}


def test_remove_leaves_no_journal_and_may_be_repeated(tmp_path: Path) -> None:
    """After remove, read says there is none; a second remove is fine."""
    journal = DeviceJournal(tmp_path / 'a.json')
    journal.record({'SERVO1_FUNCTION': 33.0})
    journal.remove()
    journal.remove()
    assert journal.read() is None


def test_a_file_that_is_not_a_journal_is_named(tmp_path: Path) -> None:
    """Garbage in the journal's place: an error naming the file, not a silent 'no journal'."""
    (tmp_path / 'a.json').write_text('{not json')
    with pytest.raises(JournalError, match=r'a\.json is not a journal'):
        DeviceJournal(tmp_path / 'a.json').read()


def test_a_journal_that_cannot_be_written_refuses_the_change(tmp_path: Path) -> None:
    """A folder that cannot be made: JournalError (the bridge then changes nothing)."""
    blocker = tmp_path / 'file'
    blocker.write_text('')
    with pytest.raises(JournalError, match=r'journal .*sub/a\.json'):
        DeviceJournal(blocker / 'sub' / 'a.json').record({'SERVO1_FUNCTION': 33.0})


def test_the_folder_is_the_parameter_then_the_environment_then_xdg(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """journal_dir: configured, else UVMS_JOURNAL_DIR, else $XDG_STATE_HOME/uvms/journal."""
    monkeypatch.setenv('UVMS_JOURNAL_DIR', str(tmp_path / 'env'))
    monkeypatch.setenv('XDG_STATE_HOME', str(tmp_path / 'xdg'))
    assert journal_dir(str(tmp_path / 'param')) == tmp_path / 'param'
    assert journal_dir() == tmp_path / 'env'
    monkeypatch.delenv('UVMS_JOURNAL_DIR')
    assert journal_dir() == tmp_path / 'xdg' / 'uvms' / 'journal'
    monkeypatch.delenv('XDG_STATE_HOME')
    assert journal_dir() == Path.home() / '.local' / 'state' / 'uvms' / 'journal'


def test_two_connections_never_share_a_journal() -> None:
    """One file per device and connection, with only safe characters in its name."""
    a = journal_name('ardusub', 'udpout:127.0.0.1:14550')
    b = journal_name('ardusub', 'udpout:127.0.0.1:14551')
    assert a != b and a == 'ardusub_udpout_127.0.0.1_14550.json'
