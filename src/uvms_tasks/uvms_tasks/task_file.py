"""Task and mission files: ContactTask goals written as YAML, checked before anything is sent.

A task file holds one task (a mapping of the keys below); a mission file holds ``mission:``,
a list of tasks sent one after another. Scenario files use the same list under their own
``mission:`` key (``parse_mission``). Every vector is in map_ned (x north, y east, z down)::

    mission:
      - name: approach                 # str, optional (default: its key, mission[0])
        path: [[1.60, 0.0, 0.20], [1.70, 0.0, 0.20]]   # X_d waypoints (m), at least 2
        time_from_start_s: [0.0, 5.0]  # one per waypoint (s), strictly increasing, first >= 0
        velocity: [[0, 0, 0], [0, 0, 0]]      # optional X_d_dot per waypoint (m/s)
        acceleration: [[0, 0, 0], [0, 0, 0]]  # optional X_d_ddot per waypoint (m/s^2)
        normal: [1.0, 0.0, 0.0]        # force direction into the surface, required, non-zero
      - half_circle:                   # the paper's reference (sec. 5.1, Fig. 7), from X0
          duration_s: 20.0             # number > 0, required (s)
          start: [1.70, 0.0, -0.10]    # X0 (m), point A; default: the controller's X_d
          radius_m: 0.1                # number > 0 (m), default 0.1
          toward: [1.0, 0.0, 0.0]      # n, default: the task's normal
          sweep: [0.0, 0.0, 1.0]       # d, default down; not parallel to toward
          points: 81                   # waypoints sampled, int in [3, 10000], default 81
        normal: [1.0, 0.0, 0.0]
        force_n: 150.0                 # F_d (N) >= 0, default 0 (motion only)
        force_ramp_s: 1.0              # ramp of F_d (s) > 0, default 1.0
        require_contact: true          # bool, default false
        start_time_s: 2.0              # when time 0 is on the controller's clock (s);
                                       # default: when the controller accepts the goal
        send_at_s: 1.5                 # a mission's sender holds the goal until the
                                       # controller's clock reaches it (s); default: at once

A task gives either ``path`` with ``time_from_start_s`` or ``half_circle``. The half circle
starts at X0: its ``start`` when given (the controller then reaches it by a transit first,
wherever it holds), else the controller's hold target when the goal is sent, so it becomes
waypoints only then (``TaskSpec.expanded``): positions with their exact velocities and
accelerations, sampled from ``uvms_control.core.law.reference.HalfCircleReference``. Integers
are accepted where numbers are expected; ``1e4`` reads as a number (YAML 1.2, as ROS 2
parameter files).
Each error is one line naming the file, the key (``mission[1].half_circle.radius_m``) and
what is expected.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, NoReturn

import numpy as np
import numpy.typing as npt
import yaml
from uvms_control.core.errors import ControlParameterError
from uvms_control.core.law.reference import HalfCircleReference

from uvms_tasks.errors import TaskFileError

FloatArray = npt.NDArray[np.float64]
Vector3 = tuple[float, float, float]

#: Keys of a task; a half circle replaces the four path keys.
PATH_KEYS = ('path', 'time_from_start_s', 'velocity', 'acceleration')
TASK_KEYS = ('name', *PATH_KEYS, 'half_circle', 'normal', 'force_n', 'force_ramp_s',
             'require_contact', 'start_time_s', 'send_at_s')
HALF_CIRCLE_KEYS = ('duration_s', 'start', 'radius_m', 'toward', 'sweep', 'points')
#: Defaults: the controller's force ramp (config/controller.yaml) and the paper's half circle.
DEFAULT_FORCE_RAMP_S = 1.0
DEFAULT_RADIUS_M = 0.1
DEFAULT_SWEEP: Vector3 = (0.0, 0.0, 1.0)
DEFAULT_POINTS = 81
MAX_POINTS = 10_000
_REPR_CHARS = 60


class Yaml12Loader(yaml.SafeLoader):
    """YAML loader that reads ``1e4`` as a float, as ROS 2 parameter files do (YAML 1.2)."""


Yaml12Loader.add_implicit_resolver(  # type: ignore[no-untyped-call]
    'tag:yaml.org,2002:float',
    re.compile(
        r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
        |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
        |\.[0-9_]+(?:[eE][-+][0-9]+)?
        |[-+]?\.(?:inf|Inf|INF)
        |\.(?:nan|NaN|NAN))$""",
        re.VERBOSE,
    ),
    list('-+0123456789.'),
)


@dataclass(frozen=True)
class HalfCircle:
    """The paper's half-circle reference (sec. 5.1), to be started from X0.

    Attributes:
        duration_s: Time to run the half circle (s).
        radius_m: r (m).
        toward: n, toward the surface in map_ned; None: the task's normal.
        sweep: d, the diameter's direction in map_ned (default down).
        points: Waypoints sampled over the duration, both ends included.
        start: X0 in map_ned (m); None: the controller's X_d when the goal is sent.
    """

    duration_s: float
    radius_m: float = DEFAULT_RADIUS_M
    toward: Vector3 | None = None
    sweep: Vector3 = DEFAULT_SWEEP
    points: int = DEFAULT_POINTS
    start: Vector3 | None = None

    def reference(self, normal: Sequence[float]) -> HalfCircleReference:
        """The reference generator, starting at t = 0 (no delay)."""
        return HalfCircleReference(radius=self.radius_m, duration=self.duration_s,
                                   start_delay=0.0, toward=self.toward or tuple(normal),
                                   sweep=self.sweep)

    def sample(
        self, start: Sequence[float], normal: Sequence[float]
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Waypoints from X0: times (s), X_d (m), X_d_dot (m/s), X_d_ddot (m/s²).

        Example:
            >>> times, x_d, _, _ = HalfCircle(duration_s=10.0, points=3).sample(
            ...     [0.0, 0.0, 0.0], [1.0, 0.0, 0.0])
            >>> np.round(x_d, 6).tolist()
            [[0.0, 0.0, 0.0], [0.1, 0.0, 0.1], [0.0, 0.0, 0.2]]
        """
        reference = self.reference(normal)
        times = np.linspace(0.0, self.duration_s, self.points)
        x0 = [float(value) for value in start]
        values = np.array([reference.evaluate_floats(float(t), x0) for t in times])
        return times, values[:, 0:3], values[:, 3:6], values[:, 6:9]


@dataclass(frozen=True, eq=False)
class TaskSpec:
    """One ContactTask goal as a file gives it (map_ned, SI units).

    Attributes:
        name: Label in logs and results (default: its key, ``mission[0]`` or ``task``).
        path: X_d waypoints (n, 3) in m; (0, 3) until a half circle is expanded.
        time_from_start_s: One time per waypoint (n,) in s.
        normal: Force direction into the surface (3,), non-zero (the server normalizes).
        force_n: F_d along the normal while in contact (N); 0: motion only.
        force_ramp_s: Ramp of F_d after first contact and down at release (s).
        require_contact: Whether a path that ends without contact fails (NO_CONTACT).
        start_time_s: When the path's time 0 is on the controller's clock (s); None: when the
            goal is accepted.
        velocity: X_d_dot per waypoint (n, 3) in m/s, or None: the server chooses.
        acceleration: X_d_ddot per waypoint (n, 3) in m/s², or None: the server chooses.
        half_circle: The half circle still to be expanded from X0, or None.
        send_at_s: A mission sends the goal once the controller's clock reaches it (s), as
            after a pilot session; None: as soon as the previous task ended.
    """

    name: str
    path: FloatArray
    time_from_start_s: FloatArray
    normal: FloatArray
    force_n: float = 0.0
    force_ramp_s: float = DEFAULT_FORCE_RAMP_S
    require_contact: bool = False
    start_time_s: float | None = None
    velocity: FloatArray | None = None
    acceleration: FloatArray | None = None
    half_circle: HalfCircle | None = None
    send_at_s: float | None = None

    @property
    def needs_start(self) -> bool:
        """Whether the waypoints depend on X0 (a half circle without its own start)."""
        return self.half_circle is not None and self.half_circle.start is None

    def expanded(self, start: Sequence[float] | None = None) -> TaskSpec:
        """The task with its half circle turned into waypoints from X0 (m).

        X0 is the half circle's own ``start``, else ``start`` (the controller's X_d). A task
        with explicit waypoints is returned unchanged.

        Raises:
            ValueError: a half circle with neither.
        """
        if self.half_circle is None:
            return self
        origin = self.half_circle.start if self.half_circle.start is not None else start
        if origin is None:
            msg = f'{self.name}: a half circle needs its start X0 (the controller X_d)'
            raise ValueError(msg)
        times, x_d, x_d_dot, x_d_ddot = self.half_circle.sample(origin, self.normal.tolist())
        return replace(self, path=x_d, time_from_start_s=times, velocity=x_d_dot,
                       acceleration=x_d_ddot, half_circle=None)


def load_task_file(path: str | Path) -> list[TaskSpec]:
    """Read a task or mission file: its tasks in the order they are to be sent.

    Raises:
        TaskFileError: The file cannot be read, is not YAML or breaks the schema.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding='utf-8')
    except OSError as exc:
        msg = f'{path}: cannot read the task file: {exc.strerror or exc}'
        raise TaskFileError(msg) from exc
    try:
        data = yaml.load(text, Loader=Yaml12Loader)  # a SafeLoader subclass
    except yaml.YAMLError as exc:
        detail = ' '.join(str(exc).split())
        msg = f'{path}: not valid YAML: {detail}'
        raise TaskFileError(msg) from exc
    return parse_task_document(data, str(path))


def parse_task_document(data: Any, source: str) -> list[TaskSpec]:
    """Validate a parsed task file (one task) or mission file (``mission:``)."""
    if not isinstance(data, dict):
        _fail(source, '', 'a mapping: one task, or mission: [tasks]', data)
    if 'mission' in data:
        extra = sorted(str(key) for key in data if key != 'mission')
        if extra:
            msg = f'{source}: key {extra[0]!r}: a mission file holds only the key mission'
            raise TaskFileError(msg)
        return parse_mission(data['mission'], source)
    return [parse_task(data, source, 'task')]


def parse_mission(value: Any, source: str, key: str = 'mission') -> list[TaskSpec]:
    """Validate a list of tasks (the ``mission:`` of a mission or scenario file).

    Args:
        value: The list as YAML gives it.
        source: The file, for the messages.
        key: Its key in the file; tasks are named ``key[i]``.
    """
    if not isinstance(value, list) or not value:
        _fail(source, key, 'a non-empty list of tasks', value)
    return [parse_task(item, source, f'{key}[{i}]') for i, item in enumerate(value)]


def parse_task(data: Any, source: str, key: str) -> TaskSpec:
    """Validate one task mapping found at ``key`` of ``source``."""
    if not isinstance(data, dict):
        _fail(source, key, 'a mapping of task keys', data)
    prefix = '' if key == 'task' else f'{key}.'
    _known_keys(data, source, prefix, TASK_KEYS)
    if 'normal' not in data:
        _missing(source, f'{prefix}normal', 'a list of 3 finite numbers, not all zero')
    normal = _vector3(data['normal'], source, f'{prefix}normal', nonzero=True)
    common: dict[str, Any] = {
        'name': _name(data, source, prefix, key),
        'normal': np.array(normal),
        'force_n': _number(data, 'force_n', source, prefix, 0.0, minimum=0.0),
        'force_ramp_s': _number(data, 'force_ramp_s', source, prefix, DEFAULT_FORCE_RAMP_S,
                                minimum=0.0, strict=True),
        'require_contact': _boolean(data, 'require_contact', source, prefix),
        'start_time_s': (None if data.get('start_time_s') is None else
                         _number(data, 'start_time_s', source, prefix, 0.0, minimum=0.0)),
        'send_at_s': (None if data.get('send_at_s') is None else
                      _number(data, 'send_at_s', source, prefix, 0.0, minimum=0.0)),
    }
    if 'half_circle' in data:
        given = [name for name in PATH_KEYS if name in data]
        if given:
            msg = (f'{source}: key {prefix + given[0]!r}: expected either half_circle or '
                   'path with time_from_start_s, not both')
            raise TaskFileError(msg)
        half_circle = _half_circle(data['half_circle'], source, f'{prefix}half_circle', normal)
        empty = np.zeros((0, 3))
        return TaskSpec(path=empty, time_from_start_s=np.zeros(0), half_circle=half_circle,
                        **common)
    if 'path' not in data:
        _missing(source, f'{prefix}path', 'waypoints with time_from_start_s, or half_circle')
    path = _points(data['path'], source, f'{prefix}path', minimum=2)
    times = _times(data.get('time_from_start_s'), source, f'{prefix}time_from_start_s',
                   len(path))
    velocity, acceleration = (
        None if data.get(name) is None
        else _points(data[name], source, f'{prefix}{name}', minimum=len(path), exact=True)
        for name in ('velocity', 'acceleration'))
    return TaskSpec(path=path, time_from_start_s=times, velocity=velocity,
                    acceleration=acceleration, **common)


def _half_circle(data: Any, source: str, key: str, normal: Vector3) -> HalfCircle:
    """Validate the ``half_circle`` mapping of a task."""
    if not isinstance(data, dict):
        _fail(source, key, f'a mapping of {", ".join(HALF_CIRCLE_KEYS)}', data)
    prefix = f'{key}.'
    _known_keys(data, source, prefix, HALF_CIRCLE_KEYS)
    if 'duration_s' not in data:
        _missing(source, f'{prefix}duration_s', 'a finite number > 0 (s)')
    points = data.get('points', DEFAULT_POINTS)
    if isinstance(points, bool) or not isinstance(points, int) or not 3 <= points <= MAX_POINTS:
        _fail(source, f'{prefix}points', f'an int in [3, {MAX_POINTS}]', points)
    half_circle = HalfCircle(
        duration_s=_number(data, 'duration_s', source, prefix, 0.0, minimum=0.0, strict=True),
        radius_m=_number(data, 'radius_m', source, prefix, DEFAULT_RADIUS_M, minimum=0.0,
                         strict=True),
        toward=_vector(data, 'toward', source, prefix, nonzero=True),
        sweep=_vector(data, 'sweep', source, prefix, nonzero=True) or DEFAULT_SWEEP,
        points=points,
        start=_vector(data, 'start', source, prefix),
    )
    try:
        half_circle.reference(normal)
    except ControlParameterError:
        # The generator refuses a sweep parallel to n (the only check not made above).
        _fail(source, f'{prefix}sweep', 'a direction not parallel to toward (or the normal)',
              data.get('sweep', list(DEFAULT_SWEEP)))
    return half_circle


def _fail(source: str, key: str, expected: str, value: Any) -> NoReturn:
    """Raise the one-line error of a value that is not what ``key`` expects."""
    text = repr(value)
    if len(text) > _REPR_CHARS:
        text = text[:_REPR_CHARS - 3] + '...'
    where = f'key {key!r}' if key else 'the document'
    msg = f'{source}: {where}: expected {expected}, got {_kind(value)} {text}'
    raise TaskFileError(msg)


def _missing(source: str, key: str, expected: str) -> NoReturn:
    """Raise the one-line error of a required key that is absent."""
    msg = f'{source}: key {key!r} is missing: expected {expected}'
    raise TaskFileError(msg)


def _kind(value: Any) -> str:
    """Human name of a YAML value's type."""
    if value is None:
        return 'null'
    names = {bool: 'bool', int: 'int', float: 'float', str: 'str', list: 'list', dict: 'mapping'}
    return names.get(type(value), type(value).__name__)


def _known_keys(data: Mapping[Any, Any], source: str, prefix: str,
                known: Sequence[str]) -> None:
    """Refuse a key the schema does not have (a typo would otherwise be silently ignored)."""
    for name in data:
        if name not in known:
            msg = (f'{source}: unknown key {prefix + str(name)!r}; expected one of '
                   f'{", ".join(known)}')
            raise TaskFileError(msg)


def _is_number(value: Any) -> bool:
    """An int or float (not a bool) that is finite."""
    return (isinstance(value, int | float) and not isinstance(value, bool)
            and math.isfinite(value))


def _number(data: Mapping[str, Any], name: str, source: str, prefix: str, default: float,
            minimum: float, strict: bool = False) -> float:
    """An optional finite number >= minimum (> minimum if strict), its unit in its name."""
    value = data.get(name, default)
    if not _is_number(value) or value < minimum or (strict and value == minimum):
        relation = '>' if strict else '>='
        suffix = name.rsplit('_', 1)[-1]
        unit = 'N' if suffix == 'n' else suffix
        _fail(source, f'{prefix}{name}', f'a finite number {relation} {minimum:g} ({unit})',
              value)
    return float(value)


def _boolean(data: Mapping[str, Any], name: str, source: str, prefix: str) -> bool:
    """An optional bool (default false)."""
    value = data.get(name, False)
    if not isinstance(value, bool):
        _fail(source, f'{prefix}{name}', 'true or false', value)
    return value


def _name(data: Mapping[str, Any], source: str, prefix: str, key: str) -> str:
    """The task's optional label."""
    value = data.get('name', key)
    if not isinstance(value, str) or not value:
        _fail(source, f'{prefix}name', 'a non-empty string', value)
    return str(value)


def _vector3(value: Any, source: str, key: str, nonzero: bool = False) -> Vector3:
    """A list of three finite numbers, non-zero if asked."""
    expected = 'a list of 3 finite numbers' + (', not all zero' if nonzero else '')
    if (not isinstance(value, list) or len(value) != 3
            or not all(_is_number(item) for item in value)
            or (nonzero and not any(value))):
        _fail(source, key, expected, value)
    return (float(value[0]), float(value[1]), float(value[2]))


def _vector(data: Mapping[str, Any], name: str, source: str, prefix: str,
            nonzero: bool = False) -> Vector3 | None:
    """An optional 3-vector key (None when absent)."""
    if data.get(name) is None:
        return None
    return _vector3(data[name], source, f'{prefix}{name}', nonzero)


def _points(value: Any, source: str, key: str, minimum: int, exact: bool = False) -> FloatArray:
    """A list of 3-vectors: at least ``minimum`` (exactly, if ``exact``: one per waypoint)."""
    count = f'{minimum}' if exact else f'at least {minimum}'
    if not isinstance(value, list) or len(value) < minimum or (exact and len(value) != minimum):
        _fail(source, key, f'a list of {count} [x, y, z] points', value)
    return np.array([_vector3(item, source, f'{key}[{i}]') for i, item in enumerate(value)])


def _times(value: Any, source: str, key: str, count: int) -> FloatArray:
    """One time per waypoint (s), strictly increasing, the first >= 0."""
    if not isinstance(value, list) or len(value) != count:
        _fail(source, key, f'a list of {count} times (s), one per waypoint', value)
    for i, item in enumerate(value):
        if not _is_number(item):
            _fail(source, f'{key}[{i}]', 'a finite number of seconds', item)
    if value[0] < 0:
        _fail(source, f'{key}[0]', 'a time >= 0 s', value[0])
    for i in range(1, count):
        if value[i] <= value[i - 1]:
            _fail(source, f'{key}[{i}]', f'a time > {value[i - 1]} s (strictly increasing)',
                  value[i])
    return np.array(value, dtype=np.float64)
