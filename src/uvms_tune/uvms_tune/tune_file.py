"""Tune files: the robot, the gains to search, the scenarios and the objective (docs/tuning.md).

Pure (no rclpy): read, check against the controller's parameter specs, and name the key of
any error (``tune.yaml: key 'gains.hybrid.force_kp.low': expected a number, got str``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from uvms_tune.control_api import CONTROLLER_PARAMETER_SPECS
from uvms_tune.errors import TuneError

#: Gains that are not controller parameters: the impedance as ω_n = sqrt(K/P) and
#: ζ = B_d / (2 sqrt(K P)), turned into ``impedance.stiffness_n_m`` and ``damping_n_s_m``.
DERIVED = {'impedance.natural_frequency_rad_s': (1e-3, 1e3),
           'impedance.damping_ratio': (1e-3, 1e2)}
#: Baselines that ``enqueue`` may name, run as the first trials in this order.
BASELINES = ('start', 'defaults', 'hand_tuned')
#: Objective weights and their defaults (docs/tuning.md).
OBJECTIVE_DEFAULTS = {'rms_force_error': 1.0, 'overshoot': 0.2, 'settling_time': 0.05,
                      'worst': 0.5}
#: Constraints on a simulated scenario and their defaults.
CONSTRAINT_DEFAULTS = {'min_saturation_scale': 0.2, 'max_contacts': 1.0}
_KEYS = {'name', 'description', 'robot', 'seed', 'trials', 'timeout_s', 'gains', 'start',
         'enqueue', 'train', 'held_out', 'objective', 'constraints'}
_SCENARIO_KEYS = {'scenario', 'duration_s', 'seeds', 'simulator'}
_SPECS = {spec.name: spec for spec in CONTROLLER_PARAMETER_SPECS}


@dataclass(frozen=True)
class GainRange:
    """One searched gain: a controller parameter (every entry of a list) or a derived one."""

    name: str
    low: float
    high: float
    log: bool = False


@dataclass(frozen=True)
class ScenarioRun:
    """One scenario run of a training or held-out set."""

    label: str
    scenario_path: Path
    duration_s: float | None
    seed: int
    simulator: Mapping[str, Any]
    key: str = ''


@dataclass(frozen=True)
class TuneFile:
    """A checked tune file (schema: docs/tuning.md)."""

    path: Path
    name: str
    robot: str
    trials: int
    gains: tuple[GainRange, ...]
    train: tuple[ScenarioRun, ...]
    held_out: tuple[ScenarioRun, ...] = ()
    description: str = ''
    seed: int = 0
    timeout_s: float = 600.0
    start: Mapping[str, Any] = field(default_factory=dict)
    enqueue: tuple[str, ...] = ('defaults', 'hand_tuned')
    objective: Mapping[str, float] = field(default_factory=lambda: dict(OBJECTIVE_DEFAULTS))
    constraints: Mapping[str, float] = field(
        default_factory=lambda: dict(CONSTRAINT_DEFAULTS))

    @property
    def train_max_wall_stiffness_n_m(self) -> float | None:
        """Stiffest wall the training runs set (N/m); None: none sets one.

        The training stability screen's wall: the held-out runs never take part in training,
        so their walls do not either.
        """
        values = [float(run.simulator['contact.stiffness_n_m']) for run in self.train
                  if 'contact.stiffness_n_m' in run.simulator]
        return max(values) if values else None


def load_tune_file(path: str | Path) -> TuneFile:
    """Read and check a tune file.

    Raises:
        TuneError: Unreadable, or not following the schema (the message names the key).
    """
    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text(encoding='utf-8'))
    except (OSError, yaml.YAMLError) as exc:
        raise TuneError(f'{path}: cannot read the tune file: {exc}') from exc
    return parse_tune_file(data, path)


def _fail(path: Path, key: str, expected: str, value: Any) -> TuneError:
    return TuneError(f"{path}: key '{key}': expected {expected}, got "
                     f'{type(value).__name__} {value!r}')


def _number(value: Any, key: str, path: Path, *, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise _fail(path, key, 'a number > 0' if positive else 'a number', value)
    if positive and value <= 0:
        raise _fail(path, key, 'a number > 0', value)
    return float(value)


def _integer(value: Any, key: str, path: Path, low: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < low:
        raise _fail(path, key, f'an integer >= {low}', value)
    return value


def _mapping(value: Any, key: str, path: Path) -> dict[str, Any]:
    if not isinstance(value, dict):
        raise _fail(path, key, 'a mapping', value)
    return value


def parse_tune_file(data: Any, path: Path) -> TuneFile:
    """Check the parsed YAML of a tune file (see ``load_tune_file``)."""
    data = _mapping(data, '<top level>', path)
    for key in data:
        if key not in _KEYS:
            raise TuneError(f"{path}: key '{key}': unknown (known: {', '.join(sorted(_KEYS))})")
    for key in ('name', 'robot', 'gains', 'train', 'trials'):
        if key not in data:
            raise TuneError(f"{path}: key '{key}': required")
    for key in ('name', 'robot', 'description'):
        if key in data and not isinstance(data[key], str):
            raise _fail(path, key, 'a string', data[key])
    gains = _gains(_mapping(data['gains'], 'gains', path), path)
    start = _mapping(data.get('start', {}), 'start', path)
    searched = {gain.name for gain in gains}
    for name, value in start.items():
        if name not in searched:
            raise TuneError(f"{path}: key 'start.{name}': not one of the tuned gains "
                            f"({', '.join(sorted(searched))})")
        _number(value, f'start.{name}', path)
    enqueue = data.get('enqueue', ['defaults', 'hand_tuned'])
    if not isinstance(enqueue, list) or any(item not in BASELINES for item in enqueue):
        raise _fail(path, 'enqueue', f'a list of {", ".join(BASELINES)}', enqueue)
    if 'start' in enqueue and not start:
        raise TuneError(f"{path}: key 'enqueue': names 'start' but the file has no 'start'")
    train = _scenarios(data['train'], 'train', path, required=True)
    held_out = _scenarios(data.get('held_out', []), 'held_out', path, required=False)
    _check_held_out(train, held_out, path)
    return TuneFile(
        path=path, name=data['name'], robot=data['robot'],
        description=data.get('description', ''),
        trials=_integer(data['trials'], 'trials', path, 1),
        seed=_integer(data.get('seed', 0), 'seed', path, 0),
        timeout_s=_number(data.get('timeout_s', 600.0), 'timeout_s', path, positive=True),
        gains=gains, start=dict(start), enqueue=tuple(enqueue),
        train=train, held_out=held_out,
        objective=_weights(data.get('objective', {}), 'objective', OBJECTIVE_DEFAULTS, path),
        constraints=_weights(data.get('constraints', {}), 'constraints', CONSTRAINT_DEFAULTS,
                             path),
    )


def _gains(data: dict[str, Any], path: Path) -> tuple[GainRange, ...]:
    if not data:
        raise TuneError(f"{path}: key 'gains': at least one gain to tune")
    gains = []
    for name, spec in data.items():
        key = f'gains.{name}'
        if name in DERIVED:
            lo_limit, hi_limit = DERIVED[name]
        elif name in _SPECS and isinstance(_SPECS[name].default, (float, list)):
            minimum, maximum = _SPECS[name].min_value, _SPECS[name].max_value
            lo_limit = -math.inf if minimum is None else float(minimum)
            hi_limit = math.inf if maximum is None else float(maximum)
        else:
            raise TuneError(f"{path}: key '{key}': not a numeric controller parameter nor one "
                            f"of {', '.join(DERIVED)}")
        spec = _mapping(spec, key, path)
        unknown = set(spec) - {'low', 'high', 'log'}
        if unknown or 'low' not in spec or 'high' not in spec:
            raise _fail(path, key, '{low: number, high: number, log: bool}', spec)
        low = _number(spec['low'], f'{key}.low', path)
        high = _number(spec['high'], f'{key}.high', path)
        log = spec.get('log', False)
        if not isinstance(log, bool):
            raise _fail(path, f'{key}.log', 'a bool', log)
        if not low < high:
            raise _fail(path, f'{key}.high', f'a number > low ({low:g})', high)
        if low < lo_limit or high > hi_limit:
            raise TuneError(f"{path}: key '{key}': [{low:g}, {high:g}] leaves the parameter's "
                            f'range [{lo_limit:g}, {hi_limit:g}]')
        if log and low <= 0:
            raise _fail(path, f'{key}.low', 'a number > 0 with log: true', low)
        gains.append(GainRange(name, low, high, log))
    derived = [gain.name for gain in gains if gain.name in DERIVED]
    if derived and ('impedance.stiffness_n_m' in data or 'impedance.damping_n_s_m' in data):
        raise TuneError(f"{path}: key 'gains': {derived[0]} sets the impedance's stiffness and "
                        'damping: tune either them or the natural frequency and damping ratio')
    return tuple(gains)


def _scenarios(data: Any, key: str, path: Path, *, required: bool) -> tuple[ScenarioRun, ...]:
    if not isinstance(data, list) or (required and not data):
        raise _fail(path, key, 'a non-empty list of scenarios' if required else 'a list', data)
    runs = []
    for index, item in enumerate(data):
        where = f'{key}[{index}]'
        item = _mapping(item, where, path)
        unknown = set(item) - _SCENARIO_KEYS
        if unknown or 'scenario' not in item:
            raise TuneError(f"{path}: key '{where}': needs 'scenario' and may have "
                            f"{', '.join(sorted(_SCENARIO_KEYS - {'scenario'}))}; got "
                            f'{sorted(item)}')
        scenario_path = _scenario_path(item['scenario'], f'{where}.scenario', path)
        duration = item.get('duration_s')
        if duration is not None:
            duration = _number(duration, f'{where}.duration_s', path, positive=True)
        seeds = item.get('seeds', [1])
        if not isinstance(seeds, list) or not seeds:
            raise _fail(path, f'{where}.seeds', 'a non-empty list of integers', seeds)
        simulator = _mapping(item.get('simulator', {}), f'{where}.simulator', path)
        for seed in seeds:
            _integer(seed, f'{where}.seeds', path, 0)
            label = f'{scenario_path.stem}#{index}/seed{seed}'
            runs.append(ScenarioRun(label, scenario_path, duration, seed, dict(simulator),
                                    where))
    return tuple(runs)


def _check_held_out(train: tuple[ScenarioRun, ...], held_out: tuple[ScenarioRun, ...],
                    path: Path) -> None:
    """Refuse a held-out run that repeats a training run (naming both).

    A held-out run must differ from every training run in its scenario file or its simulator
    parameters: a seed changes only the sensor noise (nothing in a noise-free scenario) and a
    duration only how long the same run goes on, so neither makes a run the gains were not
    tuned on.
    """
    for held in held_out:
        for run in train:
            if (held.scenario_path.resolve() == run.scenario_path.resolve()
                    and dict(held.simulator) == dict(run.simulator)):
                raise TuneError(
                    f"{path}: key '{held.key}': held-out run {held.label} repeats training run "
                    f'{run.key} ({run.label}): the same scenario and simulator parameters (a '
                    'seed changes only the sensor noise, a duration only the length); give it '
                    'another scenario or another simulator parameter (another wall stiffness, '
                    'current or start)')


def _scenario_path(value: Any, key: str, path: Path) -> Path:
    if not isinstance(value, str):
        raise _fail(path, key, 'a scenario name or file', value)
    candidate = Path(value)
    if candidate.suffix in ('.yaml', '.yml'):
        beside = candidate if candidate.is_absolute() else path.parent / candidate
        if beside.is_file():
            return beside
    # uvms_bringup is not typed: the one untyped call of this module.
    from uvms_bringup.launch_helpers import resolve_scenario_path  # type: ignore[import-untyped]

    try:
        return Path(resolve_scenario_path(value))
    except FileNotFoundError as exc:
        raise TuneError(f"{path}: key '{key}': {exc}") from exc


def _weights(data: Any, key: str, defaults: Mapping[str, float], path: Path) -> dict[str, float]:
    data = _mapping(data, key, path)
    values = dict(defaults)
    for name, value in data.items():
        if name not in defaults:
            raise TuneError(f"{path}: key '{key}.{name}': unknown (known: "
                            f"{', '.join(defaults)})")
        values[name] = _number(value, f'{key}.{name}', path)
        if values[name] < 0:
            raise _fail(path, f'{key}.{name}', 'a number >= 0', value)
    if key == 'objective' and values['worst'] > 1.0:
        raise _fail(path, 'objective.worst', 'a number in [0, 1]', values['worst'])
    return values
