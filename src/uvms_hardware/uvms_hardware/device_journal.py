"""A journal of a device's original values: written before the first change, removed after.

A bridge that changes something the device keeps (ArduSub's ``SERVOn_FUNCTION``, saved in the
autopilot) writes the values it found to a small JSON file *before* the first change, fsync'd,
and removes the file only once the restore has read every value back. A process killed in
between (SIGKILL, out of memory, power) leaves the file: the next configure, or ``uvms
hardware restore``, finds what to put back there::

    journal = DeviceJournal.for_device('ardusub', 'udpout:127.0.0.1:14550')
    journal.record({'SERVO1_FUNCTION': 33.0})   # before setting SERVO1_FUNCTION
    ...                                          # change, drive, restore
    journal.remove()                             # every value read back as recorded

Where: ``journal_dir`` (a bridge parameter, a CLI option), else ``UVMS_JOURNAL_DIR``, else
``$XDG_STATE_HOME/uvms/journal``, else ``~/.local/state/uvms/journal`` (the XDG base directory
specification's place for state that should persist across restarts). One file per device
and connection, so that two vehicles (or two test twins) never share one.
"""

from __future__ import annotations

import json
import os
import re
import time
from pathlib import Path

from uvms_hardware.errors import HardwareError

#: Environment variable that overrides the journal folder.
JOURNAL_DIR_ENV = 'UVMS_JOURNAL_DIR'


class JournalError(HardwareError):
    """A journal that cannot be written or read (the change it guards is not made)."""


def journal_dir(configured: str = '') -> Path:
    """The journal folder: ``configured``, else the environment's, else the XDG state home."""
    if configured:
        return Path(configured).expanduser()
    if os.environ.get(JOURNAL_DIR_ENV):
        return Path(os.environ[JOURNAL_DIR_ENV]).expanduser()
    state = os.environ.get('XDG_STATE_HOME') or str(Path.home() / '.local' / 'state')
    return Path(state) / 'uvms' / 'journal'


def journal_name(device: str, connection: str) -> str:
    """``<device>@<connection>.json`` with every character but ``[A-Za-z0-9._-]`` as ``_``."""
    return re.sub(r'[^A-Za-z0-9._-]', '_', f'{device}@{connection}') + '.json'


class DeviceJournal:
    """The original values of one device, on disk while the device may be left changed."""

    def __init__(self, path: Path) -> None:
        self.path = path

    @classmethod
    def for_device(cls, device: str, connection: str, folder: str = '') -> DeviceJournal:
        """The journal of ``device`` reached at ``connection`` in ``journal_dir(folder)``."""
        return cls(journal_dir(folder) / journal_name(device, connection))

    def read(self) -> dict[str, float] | None:
        """The recorded originals (name -> value), or None when there is no journal.

        Raises:
            JournalError: a file that is not a journal (named, with what is wrong).
        """
        try:
            text = self.path.read_text()
        except FileNotFoundError:
            return None
        except OSError as exc:
            raise JournalError(f'journal {self.path}: {exc}') from exc
        try:
            values = json.loads(text)['values']
            return {str(name): float(value) for name, value in values.items()}
        except (ValueError, KeyError, TypeError, AttributeError) as exc:
            raise JournalError(f'journal {self.path} is not a journal ({exc}): read it, then '
                               'remove it by hand') from exc

    def record(self, values: dict[str, float]) -> None:
        """Add originals not yet recorded (a value already there is the older, kept), fsync'd.

        Raises:
            JournalError: the file or its folder cannot be written: make no change then.
        """
        merged = dict(values)
        merged.update(self.read() or {})
        body = json.dumps({'values': merged, 'written_unix_s': time.time(),
                           'pid': os.getpid()}, indent=1, sort_keys=True)
        tmp = self.path.with_suffix('.tmp')
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            with open(tmp, 'w') as stream:
                stream.write(body)
                stream.flush()
                os.fsync(stream.fileno())
            os.replace(tmp, self.path)
            _fsync_dir(self.path.parent)
        except OSError as exc:
            raise JournalError(f'cannot write the journal {self.path}: {exc}') from exc

    def remove(self) -> None:
        """Remove the journal (everything was read back as recorded); no journal is fine."""
        try:
            self.path.unlink()
        except FileNotFoundError:
            return
        except OSError as exc:
            raise JournalError(f'cannot remove the journal {self.path}: {exc}') from exc
        _fsync_dir(self.path.parent)


def _fsync_dir(folder: Path) -> None:
    """Make a rename or unlink in ``folder`` durable (POSIX: fsync of the directory)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)
