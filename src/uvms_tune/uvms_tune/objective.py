"""The tune's objective and constraints from the scenario runs' metrics (pure).

Each scenario run gives its ``uvms report`` metrics; a run that failed, never touched the
wall, bounced, did not settle or saturated the thrusters is a violated constraint with its
reason, not a figure. So is a run missing what a constraint or the objective needs: its force
figures from the simulator's ground-truth contact force (never the controller's own estimate
F_e), its overshoot (never scored as 0) or its thruster data (the saturation constraint is
not passed unchecked). A successful one scores

    J = w_rms e_rms / F_d + w_os overshoot / 100 + w_ts t_settle

(the mid-contact RMS force error after settling, normalised by F_d; overshoot in %; settling
time in s), and a trial scores (1 - w_worst) mean(J) + w_worst max(J) over its scenarios.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

#: Objective value told to Optuna for a trial that violates a constraint: Optuna needs a
#: number, and the sampler ranks such trials by their violation, not by it.
INFEASIBLE_VALUE = 10.0
#: The figures' keys that a scenario run's summary keeps (``ScenarioFigures.as_dict``).
FIGURE_KEYS = ('desired_force_N', 'force_rms_error_N', 'overshoot_percent', 'settling_time_s',
               'first_contact_s', 'contact_count', 'saturation_scale_min', 'force_source')
#: ``force_source`` of force figures from the simulator's ground-truth contact force.
GROUND_TRUTH = 'contact'


@dataclass(frozen=True)
class ScenarioFigures:
    """What one scenario run of a trial gave.

    Attributes:
        label: The scenario run's label (tune_file.ScenarioRun.label).
        score: J of the run; None where it failed.
        reason: Why the run violates a constraint; '' when it does not.
        metrics: The run's metrics (``uvms report`` CSV keys), empty when it did not run.
    """

    label: str
    score: float | None
    reason: str
    metrics: Mapping[str, float | None]

    def as_dict(self) -> dict[str, Any]:
        """A JSON-able summary (trial user attrs, the parameter file's provenance)."""
        return {'label': self.label, 'score': self.score, 'reason': self.reason,
                **{key: self.metrics.get(key) for key in FIGURE_KEYS}}


def scenario_figures(label: str, outcome: Mapping[str, Any], weights: Mapping[str, float],
                     constraints: Mapping[str, float]) -> ScenarioFigures:
    """Score one point outcome (``execute_point``'s) or name the constraint it violates."""
    metrics = dict(outcome.get('metrics') or {})
    if outcome.get('status') != 'done':
        reason = outcome.get('reason') or 'failed'
        return ScenarioFigures(label, None, f'run failed: {reason}', metrics)
    reason = violation(metrics, constraints)
    if reason:
        return ScenarioFigures(label, None, reason, metrics)
    # violation() has checked that every figure of J is there and finite.
    f_d = abs(float(metrics['desired_force_N']))
    score = (weights['rms_force_error'] * float(metrics['force_rms_error_N']) / f_d
             + weights['overshoot'] * float(metrics['overshoot_percent']) / 100.0
             + weights['settling_time'] * float(metrics['settling_time_s']))
    return ScenarioFigures(label, score, '', metrics)


def figure(metrics: Mapping[str, Any], key: str) -> float | None:
    """A metric as a finite number; None where it is missing or not finite (NaN)."""
    value = metrics.get(key)
    if value is None or isinstance(value, (bool, str)):
        return None
    number = float(value)
    return number if math.isfinite(number) else None


def violation(metrics: Mapping[str, Any], constraints: Mapping[str, float]) -> str:
    """Why a finished run's metrics violate a constraint; '' when they do not.

    Missing data fails the run and says what is missing: force figures not from the
    ground-truth contact force, no overshoot, no thruster data.
    """
    source = metrics.get('force_source')
    if source != GROUND_TRUTH:
        return ('no ground-truth contact force: the run recorded none (/uvms/contact); the '
                "controller's own estimate F_e is not scored" if source == 'controller' else
                'no ground-truth contact force: the run does not say which force its figures '
                'are of (force_source)')
    if figure(metrics, 'first_contact_s') is None:
        return 'no contact'
    if not figure(metrics, 'desired_force_N'):
        return 'no force set-point in contact'
    contacts = figure(metrics, 'contact_count') or 0.0
    if contacts > constraints['max_contacts']:
        return f'bounced: {int(contacts)} contacts (a safety stop or a lost contact)'
    if figure(metrics, 'settling_time_s') is None or figure(metrics,
                                                           'force_rms_error_N') is None:
        return 'force did not settle within 5 % of F_d'
    if figure(metrics, 'overshoot_percent') is None:
        return 'no overshoot figure (the peak force was not measured)'
    scale = figure(metrics, 'saturation_scale_min')
    if scale is None:
        return ('no thruster data recorded (/uvms/thrusters/state): the saturation '
                'constraint cannot be checked')
    if scale < constraints['min_saturation_scale']:
        return (f'thrusters saturated: wrench scaled down to {scale:.3g} '
                f"(< {constraints['min_saturation_scale']:g})")
    return ''


@dataclass(frozen=True)
class TrialResult:
    """A trial's value and constraints as told to Optuna.

    Attributes:
        value: The aggregated objective, or ``INFEASIBLE_VALUE``.
        constraints: [stability violation, failed scenario fraction]; > 0 is violated.
        reasons: Why, one line per violated constraint.
        figures: Each scenario run's figures (empty when not simulated).
    """

    value: float
    constraints: tuple[float, float]
    reasons: tuple[str, ...]
    figures: tuple[ScenarioFigures, ...] = ()

    @property
    def feasible(self) -> bool:
        """No constraint violated."""
        return all(c <= 0.0 for c in self.constraints)


def unstable_result(margin: float, loop: str, labels: Sequence[str] = ()) -> TrialResult:
    """An unstable candidate: never simulated, infeasible by its stability margin.

    Each of ``labels`` (the runs it would have run) is a failed run saying so, so that a
    report counts them as failed instead of showing no runs.
    """
    reason = f'unstable: {loop}'
    figures = tuple(ScenarioFigures(label, None, f'not simulated: {reason}', {})
                    for label in labels)
    return TrialResult(INFEASIBLE_VALUE, (max(-margin, 1e-6), 0.0), (reason,), figures)


def aggregate(figures: Sequence[ScenarioFigures], margin: float,
              weights: Mapping[str, float]) -> TrialResult:
    """The trial's value over its scenario runs, or its violation when any run failed."""
    failed = [f for f in figures if f.score is None]
    if failed:
        reasons = tuple(f'{f.label}: {f.reason}' for f in failed)
        return TrialResult(INFEASIBLE_VALUE, (-margin, len(failed) / len(figures)), reasons,
                           tuple(figures))
    scores = [float(f.score) for f in figures if f.score is not None]
    worst = weights['worst']
    value = (1.0 - worst) * sum(scores) / len(scores) + worst * max(scores)
    return TrialResult(value, (-margin, 0.0), (), tuple(figures))
