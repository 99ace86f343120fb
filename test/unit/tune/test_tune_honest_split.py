"""Training and held-out runs kept apart: held-out walls never screen training, repeats refused."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import pytest
from uvms_tune.driver import Tuner
from uvms_tune.errors import TuneError
from uvms_tune.tune_file import load_tune_file, parse_tune_file

TUNES = Path(__file__).resolve().parents[3] / 'config' / 'tunes'
DONE = {'desired_force_N': 20.0, 'overshoot_percent': 5.0, 'settling_time_s': 1.0,
        'first_contact_s': 8.05, 'contact_count': 1, 'saturation_scale_min': 1.0,
        'force_rms_error_N': 0.1, 'force_source': 'contact'}
BASE = {
    'name': 'split', 'robot': 'bluerov2_alpha5', 'trials': 2,
    'gains': {'hybrid.force_kp': {'low': 0.01, 'high': 0.1, 'log': True}},
    'train': [{'scenario': 'bluerov2_alpha5_contact', 'duration_s': 12.0, 'seeds': [1]}],
}


class Runner:
    """Records every request; each run done with the same figures."""

    def __init__(self) -> None:
        self.requests: list[Mapping[str, Any]] = []

    def __call__(self, requests: Sequence[Mapping[str, Any]],
                 timeout_s: float) -> list[dict[str, Any]]:
        """Every request done."""
        self.requests.extend(requests)
        return [{'status': 'done', 'reason': '', 'metrics': dict(DONE)} for _ in requests]


def test_a_held_out_wall_never_screens_training_candidates(tmp_path: Path) -> None:
    """A 1e7 N/m held-out wall: the hand-tuned gains (stable to 2e5 N/m) still train."""
    tune = parse_tune_file({**BASE, 'held_out': [
        {'scenario': 'bluerov2_alpha5_contact', 'duration_s': 12.0,
         'simulator': {'contact.stiffness_n_m': 1.0e7}}]}, Path('split.yaml'))
    runner = Runner()
    tuner = Tuner(tune, tmp_path, runner)
    evaluation = tuner.evaluate(tuner.baselines()['hand_tuned'], tune.train)
    assert evaluation.stability.stable, evaluation.stability.loop
    assert len(runner.requests) == 1
    assert evaluation.result.feasible


def test_the_training_screen_is_the_same_with_or_without_held_out_runs(tmp_path: Path) -> None:
    """Adding a stiff held-out run changes no training trial's stability margin."""
    alone = Tuner(parse_tune_file(BASE, Path('a.yaml')), tmp_path / 'a', Runner())
    with_held_out = Tuner(parse_tune_file({**BASE, 'held_out': [
        {'scenario': 'bluerov2_alpha5_contact',
         'simulator': {'contact.stiffness_n_m': 3.0e5}}]}, Path('b.yaml')),
        tmp_path / 'b', Runner())
    alone.run(2)
    with_held_out.run(2)
    assert ([t.user_attrs['stability_margin'] for t in with_held_out.finished()]
            == [t.user_attrs['stability_margin'] for t in alone.finished()])


@pytest.mark.parametrize('held_out', [
    {'scenario': 'bluerov2_alpha5_contact', 'duration_s': 12.0, 'seeds': [2]},
    {'scenario': 'bluerov2_alpha5_contact', 'duration_s': 16.0, 'seeds': [7]},
    {'scenario': 'bluerov2_alpha5_contact', 'seeds': [1, 2],
     'simulator': {}},
])
def test_a_held_out_run_that_repeats_a_training_run_is_refused(
        held_out: dict[str, Any]) -> None:
    """Same scenario, same simulator parameters, another seed: refused naming both runs."""
    with pytest.raises(TuneError) as raised:
        parse_tune_file({**BASE, 'held_out': [held_out]}, Path('split.yaml'))
    message = str(raised.value)
    assert "'held_out[0]'" in message
    assert 'train[0]' in message and 'bluerov2_alpha5_contact#0/seed1' in message
    assert 'seed' in message


@pytest.mark.parametrize('held_out', [
    {'scenario': 'bluerov2_alpha5_contact', 'simulator': {'contact.stiffness_n_m': 3.0e4}},
    {'scenario': 'bluerov2_alpha5_current'},
    {'scenario': 'bluerov2_alpha5_contact',
     'simulator': {'initial.ee_position': [0.37, 0.0, -0.05]}},
])
def test_a_held_out_run_with_another_parameter_or_scenario_loads(
        held_out: dict[str, Any]) -> None:
    """Another wall, another scenario or another start: a genuine held-out run."""
    tune = parse_tune_file({**BASE, 'held_out': [held_out]}, Path('split.yaml'))
    assert len(tune.held_out) == 1


def test_a_training_override_equal_to_the_default_still_counts_as_a_repeat() -> None:
    """The comparison is of the simulator parameters given, in any order."""
    train = {'scenario': 'bluerov2_alpha5_contact',
             'simulator': {'contact.stiffness_n_m': 3.0e4, 'sensor.noise_fraction': 0.0}}
    held_out = {'scenario': 'bluerov2_alpha5_contact', 'seeds': [9],
                'simulator': {'sensor.noise_fraction': 0.0, 'contact.stiffness_n_m': 30000}}
    with pytest.raises(TuneError, match=r'train\[0\]'):
        parse_tune_file({**BASE, 'train': [train], 'held_out': [held_out]}, Path('s.yaml'))


@pytest.mark.parametrize('path', sorted(TUNES.glob('*.yaml')), ids=lambda p: p.stem)
def test_shipped_held_out_runs_differ_from_every_training_run(path: Path) -> None:
    """Each shipped held-out run has a scenario or simulator parameters no training run has."""
    tune = load_tune_file(path)
    for held in tune.held_out:
        for run in tune.train:
            assert (held.scenario_path.resolve(), dict(held.simulator)) != (
                run.scenario_path.resolve(), dict(run.simulator)), (held.label, run.label)
