"""Loggers with rcutils semantics: hierarchical levels, call-site filters, console format."""

from __future__ import annotations

import os
import sys
import threading
import time as _time
from collections.abc import Callable
from enum import IntEnum
from pathlib import Path
from types import FrameType
from typing import Any, TextIO

__all__ = [
    'LoggingSeverity',
    'RcutilsLogger',
    'clear_config',
    'get_logger',
    'get_logger_effective_level',
    'get_logger_level',
    'get_logging_directory',
    'get_logging_severity_from_string',
    'initialize',
    'set_logger_level',
    'shutdown',
]


class LoggingSeverity(IntEnum):
    """Severity of a log message (values as ``RCUTILS_LOG_SEVERITY``)."""

    UNSET = 0
    DEBUG = 10
    INFO = 20
    WARN = 30
    ERROR = 40
    FATAL = 50


_DEFAULT_FORMAT = '[{severity}] [{time}] [{name}]: {message}'
_COLORS = {
    LoggingSeverity.DEBUG: '\x1b[32m',
    LoggingSeverity.WARN: '\x1b[33m',
    LoggingSeverity.ERROR: '\x1b[31m',
    LoggingSeverity.FATAL: '\x1b[31m',
}
_COLOR_RESET = '\x1b[0m'

_lock = threading.RLock()
_levels: dict[str, int] = {}
_default_level = int(LoggingSeverity.INFO)
_stdout_logs = True
#: Output handlers of nodes with rosout enabled, by node logger name.
_rosout_handlers: dict[str, list[Callable[[int, str, str, str, str, int, int], None]]] = {}


def get_logging_severity_from_string(log_severity: str) -> LoggingSeverity:
    """Return the severity named ``log_severity`` (case-insensitive; ``warning`` is WARN).

    Raises:
        RuntimeError: If the name is not a severity.
    """
    name = log_severity.upper()
    if name == 'WARNING':
        name = 'WARN'
    try:
        return LoggingSeverity[name]
    except KeyError:
        raise RuntimeError(
            f"Unknown log severity '{log_severity}' (use DEBUG, INFO, WARN, ERROR, FATAL or UNSET)"
        ) from None


def _as_severity(level: int | LoggingSeverity | str) -> int:
    if isinstance(level, str):
        return int(get_logging_severity_from_string(level))
    return int(LoggingSeverity(level))


def _effective_level(name: str) -> int:
    while True:
        level = _levels.get(name)
        if level:
            return level
        if '.' not in name:
            return _default_level
        name = name.rpartition('.')[0]


def set_logger_level(
    name: str, level: int | LoggingSeverity | str, detailed_error: bool = False
) -> None:
    """Set the level of a logger by name (UNSET makes it inherit from its ancestors)."""
    severity = _as_severity(level)
    with _lock:
        if name == '':
            global _default_level
            _default_level = severity or int(LoggingSeverity.INFO)
        elif severity:
            _levels[name] = severity
        else:
            _levels.pop(name, None)


def get_logger_level(name: str) -> LoggingSeverity:
    """Return the level set on a logger (UNSET if none)."""
    return LoggingSeverity(_levels.get(name, 0))


def get_logger_effective_level(name: str) -> LoggingSeverity:
    """Return the level a logger uses: its own, its nearest ancestor's, or the default."""
    return LoggingSeverity(_effective_level(name))


def _set_default_level(level: int) -> None:
    set_logger_level('', level)


def _set_stdout_logs(enabled: bool) -> None:
    global _stdout_logs
    _stdout_logs = enabled


def initialize() -> None:
    """Initialize logging (nothing to do in process)."""


def shutdown() -> None:
    """Finalize logging (nothing to do in process)."""


def clear_config() -> None:
    """Forget every logger level and reset the default level to INFO."""
    global _default_level
    with _lock:
        _levels.clear()
        _default_level = int(LoggingSeverity.INFO)


def get_logging_directory() -> str:
    """Return the directory ROS 2 would write log files to (``ROS_LOG_DIR`` or ~/.ros/log)."""
    if os.environ.get('ROS_LOG_DIR'):
        return os.environ['ROS_LOG_DIR']
    ros_home = os.environ.get('ROS_HOME') or str(Path.home() / '.ros')
    return str(Path(ros_home) / 'log')


def _register_rosout(
    logger_name: str, handler: Callable[[int, str, str, str, str, int, int], None]
) -> None:
    with _lock:
        _rosout_handlers.setdefault(logger_name, []).append(handler)


def _unregister_rosout(
    logger_name: str, handler: Callable[[int, str, str, str, str, int, int], None]
) -> None:
    with _lock:
        handlers = _rosout_handlers.get(logger_name, [])
        if handler in handlers:
            handlers.remove(handler)
        if not handlers:
            _rosout_handlers.pop(logger_name, None)


def _stream() -> TextIO:
    if os.environ.get('RCUTILS_LOGGING_USE_STDOUT') == '1':
        return sys.stdout
    return sys.stderr


def _colorize(stream: TextIO) -> bool:
    setting = os.environ.get('RCUTILS_COLORIZED_OUTPUT')
    if setting is not None:
        return setting == '1'
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False


def _format(
    severity: int, name: str, message: str, function: str, file: str, line: int, stamp_ns: int
) -> str:
    seconds, nanoseconds = divmod(stamp_ns, 1_000_000_000)
    fields = {
        'severity': LoggingSeverity(severity).name,
        'name': name,
        'message': message,
        'function_name': function,
        'file_name': file,
        'line_number': str(line),
        'time': f'{seconds}.{nanoseconds:09d}',
        'time_as_nanoseconds': str(stamp_ns),
        'date_time_with_ms': _time.strftime('%Y-%m-%d %H:%M:%S', _time.localtime(seconds))
        + f'.{nanoseconds // 1_000_000:03d}',
    }
    template = os.environ.get('RCUTILS_CONSOLE_OUTPUT_FORMAT') or _DEFAULT_FORMAT
    out = []
    index = 0
    while index < len(template):
        start = template.find('{', index)
        if start < 0:
            out.append(template[index:])
            break
        end = template.find('}', start)
        if end < 0:
            out.append(template[index:])
            break
        out.append(template[index:start])
        key = template[start + 1:end]
        out.append(fields.get(key, template[start:end + 1]))
        index = end + 1
    return ''.join(out)


def _emit(severity: int, name: str, message: str, function: str, file: str, line: int) -> None:
    stamp_ns = _time.time_ns()
    if _stdout_logs:
        stream = _stream()
        text = _format(severity, name, message, function, file, line, stamp_ns)
        if _colorize(stream) and severity in _COLORS:
            text = f'{_COLORS[LoggingSeverity(severity)]}{text}{_COLOR_RESET}'
        with _lock:
            stream.write(text + '\n')
            stream.flush()
    if _rosout_handlers:
        with _lock:
            owner = name
            handlers = list(_rosout_handlers.get(owner, ()))
            while not handlers and '.' in owner:
                owner = owner.rpartition('.')[0]
                handlers = list(_rosout_handlers.get(owner, ()))
        for handler in handlers:
            handler(severity, name, message, function, file, line, stamp_ns)


class _Filters:
    """State of the call-site filters of one log call site, checked as rclpy does.

    In rclpy's order (throttle, skip_first, once), stopping at the first filter that refuses;
    a throttled call site starts as if it last logged at time 0 of its clock.
    """

    __slots__ = ('kwargs', 'last_logged_ns', 'name', 'once_done', 'severity', 'skip_done')

    def __init__(self, name: str, severity: int, kwargs: dict[str, Any]) -> None:
        self.name = name
        self.severity = severity
        self.kwargs = kwargs
        self.once_done = False
        self.skip_done = False
        self.last_logged_ns = 0

    def should_log(self) -> bool:
        kwargs = self.kwargs
        duration = kwargs.get('throttle_duration_sec')
        if duration is not None:
            clock = kwargs.get('throttle_time_source_type')
            now_ns = clock.now().nanoseconds if clock is not None else _time.time_ns()
            if now_ns < self.last_logged_ns + duration * 1e9:
                return False
            self.last_logged_ns = now_ns
        if kwargs.get('skip_first') and not self.skip_done:
            self.skip_done = True
            return False
        if kwargs.get('once'):
            if self.once_done:
                return False
            self.once_done = True
        return True


_FILTER_KWARGS = frozenset(('throttle_duration_sec', 'throttle_time_source_type', 'skip_first',
                            'once'))


class RcutilsLogger:
    """A named logger (``node.get_logger()`` or ``rclpy.logging.get_logger(name)``).

    Args:
        name: Dot-separated logger name; levels are inherited along the dots.
    """

    def __init__(self, name: str = '') -> None:
        self.name = name
        self.contexts: dict[tuple[str, str, int, int], _Filters] = {}

    def get_child(self, name: str) -> RcutilsLogger:
        """Return the logger ``<this name>.<name>``.

        Raises:
            ValueError: If ``name`` is empty.
        """
        if not name:
            raise ValueError('Child logger name must not be empty.')
        fullname = f'{self.name}.{name}' if self.name else name
        return RcutilsLogger(name=fullname)

    def set_level(self, level: int | LoggingSeverity | str) -> None:
        """Set this logger's level (UNSET inherits)."""
        set_logger_level(self.name, level)

    def get_effective_level(self) -> LoggingSeverity:
        """Return the level in effect for this logger."""
        return get_logger_effective_level(self.name)

    def is_enabled_for(self, severity: int | LoggingSeverity) -> bool:
        """Tell whether a message of ``severity`` would be emitted."""
        return int(severity) >= _effective_level(self.name)

    def log(self, message: str, severity: int | LoggingSeverity, **kwargs: Any) -> bool:
        """Log a message; return whether it was emitted.

        Args:
            message: Text to log.
            severity: Severity of the message.
            **kwargs: Call-site filters: ``once=True``, ``skip_first=True``,
                ``throttle_duration_sec`` (s) with optional ``throttle_time_source_type``
                (a Clock; system time by default); and ``name`` to log under another name.

        Raises:
            TypeError: If ``message`` is not a str or a keyword is not a known filter.
            ValueError: If a call site changes its severity, name or filters between calls.
        """
        severity = int(severity)
        if severity < _effective_level(self.name):
            return False
        if not isinstance(message, str):
            raise TypeError(
                f'log message must be a str, got {type(message).__name__}: {message!r}'
            )
        name = kwargs.pop('name', self.name)
        unknown = set(kwargs) - _FILTER_KWARGS
        if unknown:
            raise TypeError(
                f'parameter {sorted(unknown)[0]!r} is not one of the recognized logging options '
                f'{sorted(_FILTER_KWARGS)}'
            )
        if 'throttle_time_source_type' in kwargs and 'throttle_duration_sec' not in kwargs:
            raise TypeError('throttle_time_source_type needs throttle_duration_sec')
        frame = _caller_frame()
        function = frame.f_code.co_name if frame else '<unknown>'
        file = frame.f_code.co_filename if frame else '<unknown>'
        line = frame.f_lineno if frame else 0
        if kwargs:
            key = (function, file, line, frame.f_lasti if frame else 0)
            context = self.contexts.get(key)
            if context is None:
                context = _Filters(name, severity, kwargs)
                self.contexts[key] = context
            else:
                if severity != context.severity:
                    raise ValueError('Logger severity cannot be changed between calls.')
                if name != context.name:
                    raise ValueError('Logger name cannot be changed between calls.')
                if set(kwargs) != set(context.kwargs):
                    raise ValueError('Requested filters cannot be changed between calls.')
            if not context.should_log():
                return False
        _emit(severity, name, message, function, file, line)
        return True

    def debug(self, message: str, **kwargs: Any) -> bool:
        """Log a message with DEBUG severity."""
        return self.log(message, LoggingSeverity.DEBUG, **kwargs)

    def info(self, message: str, **kwargs: Any) -> bool:
        """Log a message with INFO severity."""
        return self.log(message, LoggingSeverity.INFO, **kwargs)

    def warning(self, message: str, **kwargs: Any) -> bool:
        """Log a message with WARN severity."""
        return self.log(message, LoggingSeverity.WARN, **kwargs)

    def warn(self, message: str, **kwargs: Any) -> bool:
        """Log a message with WARN severity (alias of :meth:`warning`)."""
        return self.log(message, LoggingSeverity.WARN, **kwargs)

    def error(self, message: str, **kwargs: Any) -> bool:
        """Log a message with ERROR severity."""
        return self.log(message, LoggingSeverity.ERROR, **kwargs)

    def fatal(self, message: str, **kwargs: Any) -> bool:
        """Log a message with FATAL severity."""
        return self.log(message, LoggingSeverity.FATAL, **kwargs)


def _caller_frame() -> FrameType | None:
    """Return the frame that called a logging method (outside this module)."""
    frame = sys._getframe(1)
    this_file = __file__
    while frame is not None and frame.f_code.co_filename == this_file:
        frame = frame.f_back  # type: ignore[assignment]
    return frame


def get_logger(name: str) -> RcutilsLogger:
    """Return a logger by name.

    Raises:
        ValueError: If ``name`` is empty.
    """
    if not name:
        raise ValueError('Logger name must not be empty.')
    return RcutilsLogger(name)
