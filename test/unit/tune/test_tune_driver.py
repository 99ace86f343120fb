"""The ask/tell loop with a stand-in runner: stability first, failures as constraints, resume."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import pytest
from uvms_tune.driver import CONTROL_PERIOD_S, Tuner
from uvms_tune.gains import stability
from uvms_tune.tune_file import TuneFile, parse_tune_file

DONE = {'desired_force_N': 20.0, 'overshoot_percent': 5.0, 'settling_time_s': 1.0,
        'first_contact_s': 8.05, 'contact_count': 1, 'saturation_scale_min': 1.0,
        'force_source': 'contact'}


def tune_file(low: float = 0.01, high: float = 20.0, trials: int = 8) -> TuneFile:
    """K_fp over a range whose upper part is unstable on the 1e5 N/m wall."""
    return parse_tune_file({
        'name': 'unit', 'robot': 'bluerov2_alpha5', 'trials': trials, 'seed': 5,
        'gains': {'hybrid.force_kp': {'low': low, 'high': high, 'log': True},
                  'hybrid.force_ki': {'low': 0.01, 'high': 1.0, 'log': True}},
        'train': [{'scenario': 'bluerov2_alpha5_contact', 'duration_s': 12.0, 'seeds': [1, 2]}],
    }, Path('unit.yaml'))


class Runner:
    """Counts its calls; RMS error grows with |K_fp - 0.05|; ``fail`` fails seed 2's run."""

    def __init__(self, fail: Mapping[str, Any] | None = None, stop_after: int = -1) -> None:
        self.requests: list[Mapping[str, Any]] = []
        self.fail = fail
        self.stop_after = stop_after

    def __call__(self, requests: Sequence[Mapping[str, Any]],
                 timeout_s: float) -> list[dict[str, Any]]:
        """The outcomes of ``requests``, or KeyboardInterrupt at the set trial."""
        if len(self.requests) // 2 == self.stop_after:
            raise KeyboardInterrupt
        self.requests.extend(requests)
        outcomes = []
        for request in requests:
            kp = request['overrides']['controller']['hybrid.force_kp']
            outcome = {'status': 'done', 'reason': '',
                       'metrics': {**DONE, 'force_rms_error_N': abs(kp - 0.05) * 10.0}}
            if self.fail is not None and request['seed'] == 2:
                outcome = {**outcome, **self.fail}
            outcomes.append(outcome)
        return outcomes


def test_an_unstable_candidate_is_never_simulated(tmp_path: Path) -> None:
    """Every unstable trial is infeasible with its loop named, and no request carries it."""
    runner = Runner()
    tuner = Tuner(tune_file(), tmp_path, runner)
    tuner.run(8)
    trials = tuner.finished()
    unstable = [t for t in trials if t.user_attrs['reasons'][:1] and
                t.user_attrs['reasons'][0].startswith('unstable')]
    assert unstable, 'the range should hold unstable gains'
    for trial in unstable:
        assert trial.constraints['stability'] > 0.0
    simulated = {r['overrides']['controller']['hybrid.force_kp'] for r in runner.requests}
    assert len(runner.requests) == 2 * (len(trials) - len(unstable))
    for kp in simulated:
        check = stability({**tuner.base, 'hybrid.force_kp': kp}, CONTROL_PERIOD_S, None)
        assert check.stable


def test_all_unstable_range_never_calls_the_runner(tmp_path: Path) -> None:
    """K_fp in [5, 20] is unstable throughout: zero runs, no feasible trial."""
    runner = Runner()
    tune = parse_tune_file({
        'name': 'u', 'robot': 'bluerov2_alpha5', 'trials': 3, 'enqueue': [],
        'gains': {'hybrid.force_kp': {'low': 5.0, 'high': 20.0}},
        'train': [{'scenario': 'bluerov2_alpha5_contact'}]}, Path('u.yaml'))
    tuner = Tuner(tune, tmp_path, runner)
    tuner.run(3)
    assert runner.requests == [] and tuner.best() is None


@pytest.mark.parametrize(('fail', 'reason'), [
    ({'status': 'failed', 'reason': 'the state diverged'}, 'run failed: the state diverged'),
    ({'metrics': {**DONE, 'first_contact_s': None, 'force_rms_error_N': None}}, 'no contact'),
    ({'metrics': {**DONE, 'contact_count': 3, 'force_rms_error_N': 1.0}}, 'bounced'),
    ({'metrics': {**DONE, 'saturation_scale_min': 0.05, 'force_rms_error_N': 1.0}},
     'thrusters saturated'),
])
def test_a_failing_scenario_is_a_violated_constraint_with_its_reason(
        tmp_path: Path, fail: Mapping[str, Any], reason: str) -> None:
    """Seed 2 fails: every simulated trial violates 'scenarios' by 1/2, naming run and reason."""
    tuner = Tuner(tune_file(high=0.1, trials=3), tmp_path, Runner(fail))
    tuner.run(3)
    for trial in tuner.finished():
        assert trial.constraints['scenarios'] == pytest.approx(0.5)
        assert any('seed2' in line and reason in line for line in trial.user_attrs['reasons'])
    assert tuner.best() is None


def test_baselines_are_the_first_trials(tmp_path: Path) -> None:
    """Defaults and hand-tuned (equal for this robot) are enqueued once, first."""
    tuner = Tuner(tune_file(), tmp_path, Runner())
    tuner.run(2)
    first = tuner.finished()[0]
    assert first.user_attrs['baseline'] == 'defaults, hand_tuned'
    assert first.params['hybrid.force_kp'] == pytest.approx(0.05)


def test_resume_continues_with_the_same_trials(tmp_path: Path) -> None:
    """Stopped in trial 4 then resumed: the same gains in the same order as without a stop."""
    whole = Tuner(tune_file(), tmp_path / 'whole', Runner())
    whole.run(8)
    first = Tuner(tune_file(), tmp_path / 'cut', Runner(stop_after=3))
    with pytest.raises(KeyboardInterrupt):
        first.run(8)
    assert len(first.finished()) < 8
    with pytest.raises(Exception, match=r'--resume'):
        Tuner(tune_file(), tmp_path / 'cut', Runner())
    resumed = Tuner(tune_file(), tmp_path / 'cut', Runner(), resume=True)
    resumed.run(8)
    assert [t.params for t in resumed.finished()] == [t.params for t in whole.finished()]
    assert [t.value for t in resumed.finished()] == [t.value for t in whole.finished()]
