"""Exception and warning types of uvms_recording: writing, reading and replaying recordings."""


class RecordingError(Exception):
    """A recording cannot be written or read (names the file and what is wrong)."""


class ReplayError(Exception):
    """A recording cannot be replayed or its controller re-run as asked."""


class RecordingTruncatedWarning(UserWarning):
    """A recording was cut short (e.g. the recorder crashed): only its complete chunks are read."""


__all__ = [
    'RecordingError',
    'RecordingTruncatedWarning',
    'ReplayError',
]
