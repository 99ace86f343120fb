"""The tune's figures cannot look better than they are: failures counted, missing data fails."""

from __future__ import annotations

import io
import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import pytest
from mcap.writer import Writer
from uvms_tune.driver import Tuner
from uvms_tune.finish import write_results
from uvms_tune.force_source import with_force_source
from uvms_tune.objective import ScenarioFigures, scenario_figures
from uvms_tune.report import SetFigures, report_text, reproduction_differences, summary_row
from uvms_tune.tune_file import CONSTRAINT_DEFAULTS, OBJECTIVE_DEFAULTS, parse_tune_file

DONE = {'desired_force_N': 20.0, 'overshoot_percent': 5.0, 'settling_time_s': 1.0,
        'first_contact_s': 8.05, 'contact_count': 1, 'saturation_scale_min': 1.0,
        'force_rms_error_N': 0.2, 'force_source': 'contact'}
TUNE = {
    'name': 'honest', 'robot': 'bluerov2_alpha5', 'trials': 2, 'seed': 3,
    'gains': {'hybrid.force_kp': {'low': 0.02, 'high': 0.1, 'log': True}},
    'enqueue': ['hand_tuned'],
    'train': [{'scenario': 'bluerov2_alpha5_contact', 'duration_s': 12.0, 'seeds': [1]}],
}


def score(metrics: Mapping[str, Any]) -> ScenarioFigures:
    """A finished run's figures under the default weights and constraints."""
    return scenario_figures('run#0/seed1', {'status': 'done', 'metrics': dict(metrics)},
                            OBJECTIVE_DEFAULTS, CONSTRAINT_DEFAULTS)


def cells(row: str) -> list[str]:
    """The cells of a markdown row."""
    return [cell.strip() for cell in row.strip().strip('|').split('|')]


def number(cell: str) -> float | None:
    """A cell's number; None where the cell is not one."""
    try:
        return float(cell)
    except ValueError:
        return None


def test_a_set_that_fails_more_runs_never_shows_better_figures() -> None:
    """One good run and one failed: no column shows a number better than two passed runs'."""
    passing = [score(DONE), score({**DONE, 'force_rms_error_N': 0.3})]
    better = score({**DONE, 'force_rms_error_N': 0.01, 'overshoot_percent': 0.1,
                    'settling_time_s': 0.5})
    failed = ScenarioFigures('run#1/seed1', None, 'run failed: timeout', {})
    clean = cells(summary_row('a', 'train', passing, 0.5))
    failing = cells(summary_row('b', 'train', [better, failed], 0.5))
    for index in range(2, 7):
        ours = number(failing[index])
        assert ours is None or ours >= (number(clean[index]) or 0.0), (clean, failing)
    assert failing[7] == '1 of 2' and clean[7] == '0 of 2'
    assert 'failed' in failing[2]


def test_figures_are_means_over_all_runs_failed_ones_included() -> None:
    """A bounced run's ground-truth overshoot counts in the mean of its row."""
    bounced = score({**DONE, 'contact_count': 3, 'overshoot_percent': 45.0})
    assert bounced.score is None
    row = cells(summary_row('a', 'train', [score(DONE), bounced], 0.5))
    assert number(row[5]) == pytest.approx(25.0)


def test_an_unstable_set_counts_its_runs_as_failed(tmp_path: Path) -> None:
    """Gains refused by the stability check: every run failed, not an empty row."""
    tuner = Tuner(parse_tune_file(TUNE, Path('t.yaml')), tmp_path, Runner())
    evaluation = tuner.evaluate({'hybrid.force_kp': 20.0}, tuner.tune.train)
    assert not evaluation.stability.stable
    row = cells(summary_row('tuned', 'train', list(evaluation.result.figures), 0.5))
    assert row[7] == '1 of 1'
    assert 'not simulated: unstable' in evaluation.result.figures[0].reason


def test_a_missing_overshoot_fails_the_run() -> None:
    """No overshoot figure: the run fails saying so, it never scores as 0 %."""
    figures = score({**DONE, 'overshoot_percent': None})
    assert figures.score is None and 'overshoot' in figures.reason


@pytest.mark.parametrize('value', [None, float('nan')])
def test_a_run_without_thruster_data_fails_the_saturation_constraint(
        value: float | None) -> None:
    """No thrust scale recorded: the saturation constraint fails instead of passing."""
    figures = score({**DONE, 'saturation_scale_min': value})
    assert figures.score is None and 'no thruster data' in figures.reason


@pytest.mark.parametrize(('source', 'says'), [('controller', "controller's own estimate"),
                                              (None, 'force_source')])
def test_force_figures_not_of_the_ground_truth_fail_the_run(source: str | None,
                                                              says: str) -> None:
    """The controller's own force estimate is never scored: the run fails naming what lacks."""
    figures = score({**DONE, 'force_source': source})
    assert figures.score is None
    assert 'no ground-truth contact force' in figures.reason and says in figures.reason


def mcap_with(topics: Sequence[str]) -> bytes:
    """A small MCAP holding one JSON message on each of ``topics``."""
    stream = io.BytesIO()
    writer = Writer(stream)
    writer.start()
    schema = writer.register_schema('empty', 'jsonschema', b'{}')
    for topic in topics:
        channel = writer.register_channel(topic, 'json', schema)
        writer.add_message(channel, 1, b'{}', 1)
    writer.finish()
    return stream.getvalue()


@pytest.mark.parametrize(('topics', 'source'), [
    (['/uvms/controller/state', '/uvms/contact'], 'contact'),
    (['/uvms/controller/state'], 'controller'),
])
def test_the_force_source_is_read_from_the_recording(topics: list[str], source: str) -> None:
    """Ground truth when the run recorded /uvms/contact, else the controller's estimate."""
    metrics = {key: value for key, value in DONE.items() if key != 'force_source'}
    outcome = with_force_source({'status': 'done', 'metrics': metrics,
                                 'mcap': mcap_with(topics)})
    assert outcome['metrics']['force_source'] == source


class Runner:
    """Sweep point runner stand-in: done runs; the recording (when asked) has ``topics``.

    ``changed`` is added to the metrics of every run after the first ``after`` calls.
    """

    def __init__(self, topics: Sequence[str] | None = None, after: int = 10 ** 6,
                 changed: Mapping[str, Any] | None = None) -> None:
        self.topics = topics
        self.calls = 0
        self.after = after
        self.changed = dict(changed or {})

    def __call__(self, requests: Sequence[Mapping[str, Any]],
                 timeout_s: float) -> list[dict[str, Any]]:
        """Every request done."""
        self.calls += 1
        outcomes = []
        for request in requests:
            metrics = dict(DONE)
            if self.topics is not None:
                metrics.pop('force_source')
            if self.calls > self.after:
                metrics.update(self.changed)
            mcap = (mcap_with(self.topics) if self.topics is not None and request['record']
                    else None)
            outcomes.append({'status': 'done', 'reason': '', 'metrics': metrics,
                             'mcap': mcap})
        return outcomes


def test_a_tune_whose_runs_record_no_ground_truth_has_no_feasible_trial(
        tmp_path: Path) -> None:
    """Runs without /uvms/contact: every trial fails naming the missing ground truth."""
    tuner = Tuner(parse_tune_file(TUNE, Path('t.yaml')), tmp_path,
                  Runner(topics=['/uvms/controller/state']))
    tuner.run(2)
    assert tuner.best() is None
    for trial in tuner.finished():
        assert any('no ground-truth contact force' in line
                   for line in trial.user_attrs['reasons'])


def _finish(tmp_path: Path, runner: Runner) -> tuple[str, dict[str, Any]]:
    tuner = Tuner(parse_tune_file(TUNE, Path('t.yaml')), tmp_path, runner)
    tuner.run(2)
    best = tuner.best()
    assert best is not None
    _, report = write_results(tuner, best, 2)
    provenance = json.loads((tmp_path / 'provenance.json').read_text(encoding='utf-8'))
    return report.read_text(encoding='utf-8'), provenance


def test_a_reproduced_best_trial_is_reported_as_reproduced(tmp_path: Path) -> None:
    """The rerun gives the trial's figures: report.md says so, no difference listed."""
    report, provenance = _finish(tmp_path, Runner())
    assert provenance['rerun_differences'] == []
    assert "gave the trial's J, reason and figures again" in report
    assert 'differs from the trial' not in report


def test_a_best_trial_that_does_not_reproduce_is_reported(tmp_path: Path) -> None:
    """The rerun's overshoot differs from the trial's: report.md names the run and figure."""
    report, provenance = _finish(tmp_path, Runner(after=2, changed={'overshoot_percent': 7.5}))
    assert provenance['rerun_differences']
    assert 'differs from the trial' in report
    line = next(line for line in report.splitlines() if 'overshoot_percent' in line
                and line.startswith('- '))
    assert 'bluerov2_alpha5_contact#0/seed1' in line and '5' in line and '7.5' in line


def test_reproduction_compares_reasons_too() -> None:
    """A run that passed in the trial and failed again is a difference."""
    trial = [{'label': 'r', 'score': 0.1, 'reason': '', 'overshoot_percent': 1.0}]
    again = [{'label': 'r', 'score': None, 'reason': 'run failed: timeout',
              'overshoot_percent': None}]
    differences = reproduction_differences(trial, again)
    assert any('reason' in line for line in differences)
    assert any(' J:' in line for line in differences)


def test_a_tune_without_held_out_runs_says_so() -> None:
    """No held-out runs: a stated line, no silent '-' held-out rows."""
    sets = [SetFigures(name, [score(DONE)], []) for name in ('defaults', 'hand_tuned', 'tuned')]
    text = report_text('t', sets, 0.5, [])
    assert '**No held-out runs**' in text
    assert '| held-out |' not in text
