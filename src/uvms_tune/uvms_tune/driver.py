"""The tune loop: Optuna's ask/tell in this process, each trial's scenarios run as a batch.

One trial at a time: ask Optuna for gains, check their sampled loops (``gains.stability``)
and tell an unstable set as infeasible without simulating it; otherwise run the training
scenarios through the ``runner`` (``uvms_sweep.batch.PointBatches.run`` on Ray, the same graph
as ``uvms run``) and tell the aggregated objective and the constraints. The study lives in a
journal file in the output folder (``JournalStorage`` + ``JournalFileBackend``), so a tune
stopped by Ctrl-C or a crash continues with ``resume``.

The sampler is TPE with the constraints each trial sets (the tune extra has no PyTorch,
which Optuna's GPSampler needs), re-seeded before every trial with the seed plus the number
of finished trials: a resumed tune asks the same gains an uninterrupted one would. A trial
cut short is marked failed on resume and its gains asked again first.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import optuna
from optuna.distributions import FloatDistribution
from optuna.storages import JournalStorage
from optuna.storages.journal import JournalFileBackend
from optuna.trial import FrozenTrial, TrialState

from uvms_tune.control_api import CONTROLLER_NODE_PARAMETER_SPECS
from uvms_tune.errors import TuneError
from uvms_tune.force_source import with_force_source
from uvms_tune.gains import (
    Stability,
    as_candidate,
    controller_values,
    hand_tuned,
    spec_defaults,
    stability,
)
from uvms_tune.objective import (
    ScenarioFigures,
    TrialResult,
    aggregate,
    scenario_figures,
    unstable_result,
)
from uvms_tune.tune_file import ScenarioRun, TuneFile

#: Runs point requests and returns their outcomes in order (``PointBatches.run``).
Runner = Callable[[Sequence[Mapping[str, Any]], float], list[dict[str, Any]]]
#: Called after every finished trial with (finished trials, best value or None).
Progress = Callable[[int, float | None], None]
#: The journal file in the output folder.
JOURNAL = 'journal.log'
#: Control period the stability check assumes (s): the controller's control_rate_hz default.
CONTROL_PERIOD_S = 1.0 / float(next(s.default for s in CONTROLLER_NODE_PARAMETER_SPECS
                                    if s.name == 'control_rate_hz'))
#: Names of the constraints every trial sets: the stability check's (1 - ρ_max, negated) and
#: the fraction of training scenarios that failed.
CONSTRAINTS = ('stability', 'scenarios')
#: TPE trials sampled at random before it models (Optuna's default is 10).
STARTUP_TRIALS = 5


def constraints_of(trial: FrozenTrial) -> list[float]:
    """The constraints a trial was told with (``Trial.set_constraint``); > 0 is violated."""
    return [float(trial.constraints.get(name, 1.0)) for name in CONSTRAINTS]


def sampler_for(seed: int, finished: int) -> optuna.samplers.BaseSampler:
    """TPE, seeded for the trial after ``finished`` trials.

    Optuna 5 samplers read the constraints each trial sets (``Trial.set_constraint``; the
    ``constraints_func`` argument is deprecated since 5.0): infeasible trials are ranked by
    their total violation, below every feasible one.
    """
    return optuna.samplers.TPESampler(seed=seed + finished, n_startup_trials=STARTUP_TRIALS,
                                      constant_liar=True)


@dataclass
class Evaluation:
    """One parameter set evaluated on a set of scenario runs (a trial or a report row)."""

    values: dict[str, Any]
    stability: Stability
    result: TrialResult


class Tuner:
    """A tune of one tune file in one output folder.

    Args:
        tune: The checked tune file.
        out_dir: Output folder (the journal lives there).
        runner: Runs point requests (``PointBatches.run``, or a stand-in in tests).
        resume: Continue the study in ``out_dir``; without it a journal there is refused.
    """

    def __init__(self, tune: TuneFile, out_dir: Path, runner: Runner, *,
                 resume: bool = False) -> None:
        """Open (or create) the study in ``out_dir``."""
        self.tune = tune
        self.out_dir = out_dir
        self.runner = runner
        self.base = hand_tuned(tune.robot)
        self.distributions = {gain.name: FloatDistribution(gain.low, gain.high, log=gain.log)
                              for gain in tune.gains}
        journal = out_dir / JOURNAL
        if journal.exists() and not resume:
            raise TuneError(f'{out_dir} holds a tune already ({JOURNAL}): add --resume to '
                            'continue it, or give another --out')
        out_dir.mkdir(parents=True, exist_ok=True)
        storage = JournalStorage(JournalFileBackend(str(journal)))
        optuna.logging.set_verbosity(optuna.logging.WARNING)
        fresh = not journal.exists() or not optuna.get_all_study_names(storage)
        self.study = optuna.create_study(study_name=tune.name, storage=storage,
                                         direction='minimize', load_if_exists=True,
                                         sampler=sampler_for(tune.seed, 0))
        if fresh:
            self._enqueue_baselines()
        else:
            self._requeue_cut_short()

    def baselines(self) -> dict[str, dict[str, float]]:
        """The baseline candidates by name: ``start`` (if given), ``defaults``, ``hand_tuned``."""
        found = {'defaults': as_candidate(spec_defaults(), self.tune.gains),
                 'hand_tuned': as_candidate(self.base, self.tune.gains)}
        if self.tune.start:
            found['start'] = {**found['hand_tuned'], **self.tune.start}
        return found

    def _enqueue_baselines(self) -> None:
        found = self.baselines()
        queued: list[tuple[dict[str, float], list[str]]] = []
        for name in self.tune.enqueue:
            for params, names in queued:
                if params == found[name]:
                    names.append(name)
                    break
            else:
                queued.append((found[name], [name]))
        for params, names in queued:
            self.study.enqueue_trial(params, user_attrs={'baseline': ', '.join(names)})

    def _requeue_cut_short(self) -> None:
        """Trials left running by a crash or Ctrl-C: failed, and their gains asked again."""
        for trial in self.study.get_trials(deepcopy=False, states=(TrialState.RUNNING,)):
            self.study.tell(trial.number, state=TrialState.FAIL)
            self.study.enqueue_trial(trial.params, user_attrs=dict(trial.user_attrs))

    def finished(self) -> list[FrozenTrial]:
        """Trials told with a value (feasible or not), in order."""
        return self.study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,))

    def best(self) -> FrozenTrial | None:
        """The feasible trial of least objective (the first of equals); None: none feasible."""
        feasible = [t for t in self.finished()
                    if all(c <= 0.0 for c in constraints_of(t)) and t.value is not None]
        return min(feasible, key=lambda t: (t.value, t.number)) if feasible else None

    def run(self, trials: int, progress: Progress | None = None) -> None:
        """Run trials until ``trials`` have finished (those of a resumed study count)."""
        while (done := len(self.finished())) < trials:
            self.study.sampler = sampler_for(self.tune.seed, done)
            trial = self.study.ask(self.distributions)
            evaluation = self.evaluate(trial.params, self.tune.train)
            result = evaluation.result
            for name, value in zip(CONSTRAINTS, result.constraints, strict=True):
                trial.set_constraint(name, value)
            trial.set_user_attr('reasons', list(result.reasons))
            trial.set_user_attr('stability_margin', evaluation.stability.margin)
            trial.set_user_attr('stability_loop', evaluation.stability.loop)
            trial.set_user_attr('figures', [f.as_dict() for f in result.figures])
            trial.set_user_attr('controller', json.loads(json.dumps(evaluation.values)))
            self.study.tell(trial, result.value)
            if progress is not None:
                best = self.best()
                progress(done + 1, None if best is None else best.value)

    def evaluate(self, candidate: Mapping[str, float], runs: Sequence[ScenarioRun],
                 recordings: dict[str, bytes] | None = None, label: str = '') -> Evaluation:
        """Check a candidate's stability, then (if stable) run it on ``runs`` and score it.

        ``recordings`` (if given) receives the MCAP of the first run under ``label``.
        """
        values = controller_values(candidate, self.base)
        check = stability({**self.base, **values}, CONTROL_PERIOD_S,
                          self.tune.train_max_wall_stiffness_n_m)
        if not check.stable:
            return Evaluation(values, check, unstable_result(check.margin, check.loop,
                                                             [run.label for run in runs]))
        figures = self.run_scenarios(values, runs, recordings, label)
        return Evaluation(values, check, aggregate(figures, check.margin, self.tune.objective))

    def run_scenarios(self, values: Mapping[str, Any], runs: Sequence[ScenarioRun],
                      recordings: dict[str, bytes] | None = None,
                      label: str = '') -> list[ScenarioFigures]:
        """Each run's figures for controller parameters ``values`` (one batch on the runner).

        Every run is recorded: its recording says whether its force figures are the
        ground truth's (``force_source.with_force_source``).
        """
        from uvms_sweep.batch import point_request

        requests = [point_request(run.label, run.scenario_path, run.duration_s or
                                  _scenario_duration(run.scenario_path), run.seed,
                                  {'controller': dict(values), 'simulator': run.simulator},
                                  record=True)
                    for run in runs]
        outcomes = [with_force_source(outcome)
                    for outcome in self.runner(requests, self.tune.timeout_s)]
        if recordings is not None and outcomes and outcomes[0].get('mcap'):
            recordings[label] = outcomes[0]['mcap']
        return [scenario_figures(run.label, outcome, self.tune.objective,
                                 self.tune.constraints)
                for run, outcome in zip(runs, outcomes, strict=True)]


def _scenario_duration(path: Path) -> float:
    """A scenario file's duration_s (s)."""
    from uvms_scenarios.scenario import load_scenario

    return float(load_scenario(path).duration_s)
