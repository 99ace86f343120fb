"""The end of a tune: evaluate the defaults, the hand-tuned and the tuned gains, write it all.

The training figures of a set come from its trial where the study has one (the enqueued
baselines, the best trial); the rest, and every held-out run, are run here in one batch per
set. The first training run of the defaults and of the tuned gains runs once more, recorded,
for the force figure; the tuned one's figures go into the provenance as ``rerun_figures``
and are compared with the best trial's (the runs are lockstep and seeded, so they should be
equal): any difference is listed in report.md and as ``rerun_differences``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from optuna.trial import FrozenTrial

from uvms_tune.driver import Tuner
from uvms_tune.objective import ScenarioFigures
from uvms_tune.output import git_commit, write_gains
from uvms_tune.report import (
    SetFigures,
    draw_figures,
    report_text,
    reproduction_differences,
    reproduction_text,
)


def figures_from_attrs(items: list[dict[str, Any]]) -> list[ScenarioFigures]:
    """Scenario figures back from a trial's ``figures`` user attr."""
    return [ScenarioFigures(item['label'], item['score'], item['reason'], item) for item in items]


def _trial_of(tuner: Tuner, name: str) -> FrozenTrial | None:
    """The finished trial of baseline ``name``, or of the same gains; None: none."""
    params = tuner.baselines()[name]
    for trial in tuner.finished():
        if (name in str(trial.user_attrs.get('baseline', '')).split(', ')
                or trial.params == params):
            return trial
    return None


def write_results(tuner: Tuner, best: FrozenTrial, trials: int) -> tuple[Path, Path]:
    """Write tuned_gains.yaml, provenance.json, report.md and figures/; their two paths."""
    tune = tuner.tune
    baselines = tuner.baselines()
    recordings: dict[str, bytes] = {}
    sets = []
    for name in ('defaults', 'hand_tuned', 'tuned'):
        trial = best if name == 'tuned' else _trial_of(tuner, name)
        candidate = dict(best.params) if name == 'tuned' else baselines[name]
        if trial is not None and trial.user_attrs.get('figures'):
            train = figures_from_attrs(trial.user_attrs['figures'])
        else:
            train = list(tuner.evaluate(candidate, tune.train).result.figures)
        held_out: list[ScenarioFigures] = []
        if tune.held_out:
            held_out = list(tuner.evaluate(candidate, tune.held_out).result.figures)
        sets.append(SetFigures(name, train, held_out))
    # The force figure's runs: the first training run again, recorded; the tuned one is
    # also the check that the best trial's figures reproduce.
    tuner.evaluate(baselines['defaults'], tune.train[:1], recordings, 'defaults')
    rerun = tuner.evaluate(dict(best.params), tune.train[:1], recordings, 'tuned')
    rerun_figures = [f.as_dict() for f in rerun.result.figures]
    differences = reproduction_differences(best.user_attrs['figures'], rerun_figures)
    provenance = {
        'robot': tune.robot, 'tune_file': str(tune.path), 'tune_name': tune.name,
        'trial': best.number, 'trials': len(tuner.finished()), 'budget': trials,
        'objective': float(best.value or 0.0), 'params': dict(best.params),
        'stability_margin': float(best.user_attrs['stability_margin']),
        'stability_loop': best.user_attrs['stability_loop'],
        'figures': best.user_attrs['figures'],
        'held_out_figures': [f.as_dict() for f in sets[-1].held_out],
        'rerun_figures': rerun_figures, 'rerun_differences': differences,
        'commit': git_commit(Path(__file__).parent), 'seed': tune.seed,
    }
    gains_file = write_gains(tuner.out_dir, best.user_attrs['controller'], provenance)
    notes = [f'Robot `{tune.robot}`, tune file `{tune.path}`, {len(tuner.finished())} trials '
             f'(seed {tune.seed}); best trial {best.number}, objective {best.value:.4g}, '
             f'stability margin {provenance["stability_margin"]:.4g}; commit '
             f'{provenance["commit"]}.',
             '', 'Figures: `figures/best_objective.png`, `figures/gains.png`'
             + (', `figures/force.png`' if recordings else '') + '.']
    report = tuner.out_dir / 'report.md'
    reproduction = reproduction_text(tune.train[0].label, differences)
    report.write_text(report_text(tune.name, sets, tune.objective['worst'], notes,
                                  reproduction) + '\n', encoding='utf-8')
    draw_figures(tuner.out_dir, tuner.finished(), tune.gains, recordings)
    return gains_file, report
