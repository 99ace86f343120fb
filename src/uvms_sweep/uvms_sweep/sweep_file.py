"""Sweep files: a grid of scenario runs over parameter axes, checked before anything runs.

A sweep file (``config/sweeps/NAME.yaml``, schema in docs/sweeps.md) names a base scenario and
the axes to vary, each a node parameter by its dotted scenario name::

    name: stiffness_model_error            # str, required
    description: K_e x model error         # str, optional
    scenario: case4_model_error            # str, required: file path (relative to the sweep
                                           #   file) or a name of config/scenarios/NAME.yaml
    duration_s: 13.0                       # number > 0, optional: the scenario's
    seeds: [1, 2]                          # list of int >= 0, optional: [the scenario's seed]
    timeout_s: 600.0                       # number > 0, optional (600): wall time per point
    record: false                          # bool, optional: keep each point's MCAP
    params_files: [timed.yaml]             # list of str, optional: ROS 2 parameter files
                                           #   over the scenario, before the axes (below)
    axes:                                  # mapping, required: 1 or more axes
      simulator.contact.stiffness_n_m: {logspace: [1.0e+3, 1.0e+6, 7]}
      controller.model.mass_scale: {linspace: [0.5, 1.5, 5]}
      controller.mode: [fuzzy, hybrid]     # or a list of values
    metrics: [force_rms_error_N, overshoot_percent]   # required: `uvms report` CSV columns

A ``params_files`` entry is a path relative to the sweep file, absolute, or
``robots/ROBOT/FILE`` (a file of a robot folder, wherever uvms_description is installed); each
is applied to every point as ``uvms run --params-file`` applies it (``validate.check_sweep``).

This module is pure (no rclpy): it reads, validates and expands the grid. Whether each axis
names a parameter its node declares, with that type, is checked by ``sweep_validate``.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from uvms_analysis.report import COLUMNS, LABEL_KEYS
from uvms_scenarios.scenario import (
    _NAME_SEGMENT,
    NODE_SECTIONS,
    ParameterValue,
    ScenarioError,
    _parameter_value,
    read_yaml_file,
)
from uvms_scenarios.scenario import type_error_message as _type_error
from uvms_scenarios.scenario import yaml_kind as _kind

#: Node sections an axis may vary (the recorder's parameters change no result).
AXIS_NODES = tuple(node for node in NODE_SECTIONS if node != 'recorder')
#: Metrics a sweep can tabulate and map: the numeric columns of ``uvms report --format csv``.
METRIC_KEYS = tuple(column.key for column in COLUMNS if column.key not in LABEL_KEYS)
#: Wall-clock limit of one point when the file sets none (s).
DEFAULT_TIMEOUT_S = 600.0
#: Largest number of points one sweep may have (a typo in n should not queue a million runs).
MAX_POINTS = 100_000

_REQUIRED = ('name', 'scenario', 'axes', 'metrics')
_OPTIONAL = ('description', 'duration_s', 'seeds', 'timeout_s', 'record', 'params_files')
_KNOWN_KEYS = (*_REQUIRED, *_OPTIONAL)
_SPACINGS = ('linspace', 'logspace')
_MAX_SEED = 2**31 - 1


class SweepError(ValueError):
    """A sweep file cannot be read or does not follow the schema; the message names the key."""


@dataclass(frozen=True)
class Axis:
    """One parameter varied over a list of values.

    Attributes:
        name: Dotted scenario name, ``NODE.PARAMETER`` (``controller.model.mass_scale``).
        values: The values, in order.
        spacing: ``list``, ``linspace`` or ``logspace`` (figures use a log scale for the last).
    """

    name: str
    values: tuple[ParameterValue, ...]
    spacing: str = 'list'

    @property
    def node(self) -> str:
        """Node whose parameter this is."""
        return self.name.split('.', 1)[0]

    @property
    def parameter(self) -> str:
        """Parameter name within its node (dotted)."""
        return self.name.split('.', 1)[1]


@dataclass(frozen=True)
class SweepPoint:
    """One run of a sweep: one value per axis and a seed.

    Attributes:
        point_id: Stable key of the point (hash of scenario, duration, seed and values).
        index: Index of each axis's value (grid coordinates).
        values: Axis name to value.
        seed: Sensor noise seed of the run.
    """

    point_id: str
    index: tuple[int, ...]
    values: Mapping[str, ParameterValue]
    seed: int


@dataclass(frozen=True)
class Sweep:
    """A validated sweep.

    Attributes:
        path: File the sweep was read from.
        name: Short identifier.
        description: What the sweep maps.
        scenario_path: The base scenario file.
        duration_s: Simulated duration of each point (s); None: the scenario's.
        seeds: Seeds of each grid point; empty: the scenario's seed.
        timeout_s: Wall-clock limit of one point, start-up included (s).
        record: Keep each point's recording (DIR/mcap/POINT.mcap).
        axes: The axes, in file order (the first is the figures' x axis).
        metrics: ``uvms report`` CSV column names to map.
        params_files: ROS 2 parameter files applied to every point, in order, before the axes.
    """

    path: Path
    name: str
    description: str
    scenario_path: Path
    duration_s: float | None
    seeds: tuple[int, ...]
    timeout_s: float
    record: bool
    axes: tuple[Axis, ...]
    metrics: tuple[str, ...]
    params_files: tuple[Path, ...] = ()

    def points(self, scenario_name: str, duration_s: float, default_seed: int,
               set_over: Mapping[str, Mapping[str, Any]] | None = None) -> list[SweepPoint]:
        """Every point of the grid, seeds innermost, in axis order (first axis slowest).

        Args:
            scenario_name: Name of the base scenario (part of each point's key).
            duration_s: Simulated duration of each run (s, part of the key).
            default_seed: Seed when the sweep lists none (the scenario's).
            set_over: What the parameter files and ``--ideal-devices`` set over the base
                scenario's own parameters (``overrides_set_over``; part of the key).
        """
        seeds = self.seeds or (default_seed,)
        grid = itertools.product(*(range(len(axis.values)) for axis in self.axes))
        points = []
        for index in grid:
            values = {axis.name: axis.values[i] for axis, i in zip(self.axes, index, strict=True)}
            for seed in seeds:
                key = point_id(scenario_name, duration_s, seed, values, set_over)
                points.append(SweepPoint(key, tuple(index), values, seed))
        return points


def point_id(
    scenario_name: str, duration_s: float, seed: int, values: Mapping[str, ParameterValue],
    set_over: Mapping[str, Mapping[str, Any]] | None = None,
) -> str:
    """Key of a point: 12 hex digits of SHA-256 over scenario, duration, seed and values.

    ``set_over`` (node to parameter to value: what parameter files and ``--ideal-devices`` set
    over the base scenario's own parameters) is in the key when it sets anything, so a run
    with other files or flags into the same ``--out`` runs its points again; a sweep without
    them keeps the keys it always had.
    """
    key: dict[str, Any] = {'scenario': scenario_name, 'duration_s': float(duration_s),
                           'seed': int(seed), 'values': dict(values)}
    if set_over:
        key['set_over'] = {node: dict(params) for node, params in set_over.items()}
    text = json.dumps(key, sort_keys=True)
    return hashlib.sha256(text.encode('utf-8')).hexdigest()[:12]


def overrides_set_over(
    own: Mapping[str, Mapping[str, Any]], overrides: Mapping[str, Mapping[str, Any]]
) -> dict[str, dict[str, Any]]:
    """The parameters of ``overrides`` that the scenario file's ``own`` does not set so.

    Both map node to parameter to value; the result holds only nodes with such a parameter.
    """
    missing = object()
    set_over = {}
    for node, values in overrides.items():
        theirs = own.get(node, {})
        changed = {name: value for name, value in values.items()
                   if theirs.get(name, missing) != value}
        if changed:
            set_over[node] = changed
    return set_over


def load_sweep(path: str | Path) -> Sweep:
    """Read and validate a sweep file.

    Raises:
        SweepError: The file is missing, not YAML, has an unknown key, misses a required key
            or holds a value of the wrong type; the message names the file and the key.
    """
    path = Path(path)
    return parse_sweep(read_yaml_file(path, 'sweep file', SweepError), path)


def parse_sweep(data: Any, path: Path) -> Sweep:
    """Validate the parsed YAML document of a sweep file (see ``load_sweep``)."""
    if not isinstance(data, dict):
        raise SweepError(f'{path}: expected a mapping of sweep keys, got {_kind(data)}')
    for key in data:
        if key not in _KNOWN_KEYS:
            msg = f'{path}: unknown key {key!r}; a sweep has the keys {", ".join(_KNOWN_KEYS)}'
            raise SweepError(msg)
    for key in _REQUIRED:
        if key not in data:
            raise SweepError(f'{path}: missing required key {key!r}')
    name = _string(data, 'name', path)
    description = _string(data, 'description', path) if 'description' in data else ''
    scenario = _string(data, 'scenario', path)
    duration = None
    if 'duration_s' in data:
        duration = _positive(data['duration_s'], 'duration_s', path)
    timeout = DEFAULT_TIMEOUT_S
    if 'timeout_s' in data:
        timeout = _positive(data['timeout_s'], 'timeout_s', path)
    record = data.get('record', False)
    if not isinstance(record, bool):
        raise SweepError(_type_error(path, 'record', 'bool', record))
    seeds = _seeds(data.get('seeds'), path)
    axes = _axes(data['axes'], path)
    metrics = _metrics(data['metrics'], path)
    size = math.prod(len(axis.values) for axis in axes) * max(len(seeds), 1)
    if size > MAX_POINTS:
        msg = f"{path}: key 'axes': {size} points, more than the {MAX_POINTS} a sweep may have"
        raise SweepError(msg)
    return Sweep(
        path=path,
        name=name,
        description=description,
        scenario_path=_scenario_path(scenario, path),
        duration_s=duration,
        seeds=seeds,
        timeout_s=timeout,
        record=record,
        axes=axes,
        metrics=metrics,
        params_files=_params_files(data.get('params_files'), path),
    )


def expand_axis(spec: Any, key: str, path: Path) -> tuple[tuple[ParameterValue, ...], str]:
    """Values and spacing of one axis: a list, ``{linspace: [a, b, n]}`` or ``{logspace: ...}``.

    ``linspace`` gives n evenly spaced values from a to b (``numpy.linspace``); ``logspace``
    gives n values from a to b evenly spaced on a log scale (``numpy.geomspace``: a and b are
    the end values, not exponents, and both > 0).

    Raises:
        SweepError: The message names the key ``axes.NAME`` and what was expected.
    """
    if isinstance(spec, list):
        if not spec:
            raise SweepError(f'{path}: key {key!r}: expected a non-empty list of values')
        try:
            values = tuple(_parameter_value(value, key, path) for value in spec)
        except ScenarioError as exc:
            raise SweepError(str(exc)) from exc
        return _homogeneous(values, key, path), 'list'
    if isinstance(spec, dict) and len(spec) == 1 and next(iter(spec)) in _SPACINGS:
        spacing, arguments = next(iter(spec.items()))
        where = f'{key}.{spacing}'
        if not (isinstance(arguments, list) and len(arguments) == 3):
            raise SweepError(_type_error(path, where, '[start, stop, count]', arguments))
        start, stop, count = arguments
        for name, value in (('start', start), ('stop', stop)):
            if isinstance(value, bool) or not isinstance(value, int | float) or not (
                math.isfinite(value)
            ):
                raise SweepError(_type_error(path, where, f'a finite number as {name}', value))
        if isinstance(count, bool) or not isinstance(count, int) or count < 1:
            raise SweepError(_type_error(path, where, 'an int >= 1 as count', count))
        if spacing == 'logspace':
            if start <= 0.0 or stop <= 0.0:
                msg = (f'{path}: key {where!r}: logspace needs start and stop > 0 (end values, '
                       f'not exponents), got {start} and {stop}')
                raise SweepError(msg)
            grid = np.geomspace(float(start), float(stop), count)
        else:
            grid = np.linspace(float(start), float(stop), count)
        # Rounded to 12 significant digits so that 1e3..1e6 gives 1e4, not 9999.999999999998.
        return tuple(float(f'{value:.12g}') for value in grid), spacing
    expected = 'a list of values, {linspace: [start, stop, count]} or {logspace: [...]}'
    raise SweepError(_type_error(path, key, expected, spec))


def _axes(data: Any, path: Path) -> tuple[Axis, ...]:
    """The ``axes`` mapping: dotted node parameter name to its values."""
    if not isinstance(data, dict) or not data:
        raise SweepError(_type_error(path, 'axes', 'a non-empty mapping of axes', data))
    axes = []
    for name, spec in data.items():
        key = f'axes.{name}'
        if not isinstance(name, str) or '.' not in name:
            msg = (f'{path}: key {key!r}: an axis is NODE.PARAMETER with NODE one of '
                   f'{", ".join(AXIS_NODES)} (e.g. controller.model.mass_scale)')
            raise SweepError(msg)
        node, parameter = name.split('.', 1)
        if node not in AXIS_NODES:
            msg = (f'{path}: key {key!r}: unknown node {node!r}; expected one of '
                   f'{", ".join(AXIS_NODES)}')
            raise SweepError(msg)
        if not all(_NAME_SEGMENT.match(segment) for segment in parameter.split('.')):
            msg = (f'{path}: key {key!r}: a parameter name is dotted segments of letters, '
                   'digits and underscores, not starting with a digit')
            raise SweepError(msg)
        if name == 'simulator.sensor.seed':
            raise SweepError(f"{path}: key {key!r}: list the seeds under 'seeds', not as an axis")
        values, spacing = expand_axis(spec, key, path)
        axes.append(Axis(name, values, spacing))
    return tuple(axes)


def _homogeneous(
    values: tuple[ParameterValue, ...], key: str, path: Path
) -> tuple[ParameterValue, ...]:
    """One type per axis; ints mixed with floats become floats (ROS typing is strict)."""
    kinds = {_value_kind(value) for value in values}
    if kinds <= {'int', 'float'} and len(kinds) == 2:
        return tuple(float(value) for value in values)  # type: ignore[arg-type]
    if kinds <= {'list[int]', 'list[float]'} and len(kinds) == 2:
        return tuple([float(item) for item in value] for value in values)  # type: ignore[union-attr]
    if len(kinds) > 1:
        msg = f'{path}: key {key!r}: values of one axis must have one type, got {sorted(kinds)}'
        raise SweepError(msg)
    return values


def _value_kind(value: ParameterValue) -> str:
    """Type name of a value, lists by their item type."""
    if isinstance(value, list):
        return f'list[{type(value[0]).__name__}]'
    return type(value).__name__


def _metrics(data: Any, path: Path) -> tuple[str, ...]:
    """The ``metrics`` list: names of ``uvms report``'s CSV columns."""
    if not isinstance(data, list) or not data:
        raise SweepError(_type_error(path, 'metrics', 'a non-empty list of metric names', data))
    for i, name in enumerate(data):
        if name not in METRIC_KEYS:
            msg = (f'{path}: key metrics[{i}]: unknown metric {name!r}; expected one of '
                   f'{", ".join(METRIC_KEYS)}')
            raise SweepError(msg)
    return tuple(dict.fromkeys(data))


def _seeds(data: Any, path: Path) -> tuple[int, ...]:
    """The ``seeds`` list (empty when absent)."""
    if data is None:
        return ()
    if not isinstance(data, list) or not data:
        raise SweepError(_type_error(path, 'seeds', 'a non-empty list of int', data))
    for i, seed in enumerate(data):
        if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed <= _MAX_SEED:
            raise SweepError(_type_error(path, f'seeds[{i}]', f'an int in [0, {_MAX_SEED}]', seed))
    return tuple(dict.fromkeys(data))


def _params_files(data: Any, path: Path) -> tuple[Path, ...]:
    """The ``params_files`` list: each an existing file (empty when absent)."""
    if data is None:
        return ()
    if not isinstance(data, list) or not data:
        raise SweepError(_type_error(path, 'params_files', 'a non-empty list of file paths', data))
    files = []
    for i, entry in enumerate(data):
        key = f'params_files[{i}]'
        if not isinstance(entry, str) or not entry:
            raise SweepError(_type_error(path, key, 'a file path', entry))
        candidates = [path.parent / entry]
        if Path(entry).parts[0] == 'robots' and not Path(entry).is_absolute():
            from uvms_description import robots_directory

            candidates.append(robots_directory().joinpath(*Path(entry).parts[1:]))
        found = next((file for file in candidates if file.is_file()), None)
        if found is None:
            tried = ', '.join(str(file) for file in candidates)
            raise SweepError(f'{path}: key {key!r}: no file {entry!r} (looked for {tried})')
        files.append(found)
    return tuple(files)


def _scenario_path(scenario: str, path: Path) -> Path:
    """The base scenario: a path relative to the sweep file, or a name of config/scenarios."""
    from uvms_bringup.launch_helpers import resolve_scenario_path

    candidate = Path(scenario)
    if candidate.suffix in ('.yaml', '.yml') and not candidate.is_absolute():
        beside = path.parent / candidate
        if beside.is_file():
            return beside
    try:
        return resolve_scenario_path(scenario)
    except FileNotFoundError as error:
        msg = f"{path}: key 'scenario': {error} (a path or a name)"
        raise SweepError(msg) from None


def _positive(value: Any, key: str, path: Path) -> float:
    """A finite number > 0."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise SweepError(_type_error(path, key, 'a number > 0', value))
    if not (math.isfinite(value) and value > 0.0):
        raise SweepError(f'{path}: key {key!r}: expected a number > 0, got {value}')
    return float(value)


def _string(data: Mapping[str, Any], key: str, path: Path) -> str:
    """Read a string field."""
    value = data[key]
    if not isinstance(value, str):
        raise SweepError(_type_error(path, key, 'str', value))
    return value



def axis_labels(axis: Axis) -> list[str]:
    """Tick labels of an axis's values (3 significant digits for numbers)."""
    return [_label(value) for value in axis.values]


def _label(value: ParameterValue | Sequence[Any]) -> str:
    """A value as a short label."""
    if isinstance(value, bool) or isinstance(value, str):
        return str(value)
    if isinstance(value, int | float):
        return f'{value:.3g}'
    return '[' + ', '.join(_label(item) for item in value) + ']'
