"""The identification's pipeline: recordings -> series -> known terms -> fit -> predictions."""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from uvms_identify.errors import IdentifyError
from uvms_identify.fit import HullFit, fit_hull
from uvms_identify.known_terms import ZERO_HULL, known_forces, model_with_hull
from uvms_identify.predict import horizon_errors
from uvms_identify.recording import MIN_SEGMENT_S, Series, read_series, segments
from uvms_identify.regressor import hull_regressor
from uvms_identify.robot_data import RobotData

FloatArray = NDArray[np.float64]

#: Fraction of each recording held out (its end) for the prediction figures.
HELD_OUT_FRACTION = 0.3
HORIZONS_S = (1.0, 10.0)
#: Delays searched between the recorded thrusts and the force they make (s): the thruster's
#: lag and the command's transport, as one delay (the recorded thrust at t acts at t + d).
DELAYS_S = tuple(round(float(d), 3) for d in np.arange(-0.04, 0.0801, 0.005))


@dataclass
class Identification:
    """The result of ``identify``.

    Attributes:
        robot: The robot folder of the prior (the current model).
        recordings: The recordings read.
        fit: The fitted hull terms.
        prior: The robot folder's theta.
        training, held_out: The series the fit used, and those it did not.
        errors: Per model ('identified', 'current') and horizon: RMS velocity error (6,).
        windows: Per horizon, the number of held-out windows.
        delay_s: The delay between the recorded thrusts and the force that fits best (s).
    """

    robot: RobotData
    recordings: list[Path]
    fit: HullFit
    prior: FloatArray
    training: list[Series]
    held_out: list[Series]
    errors: dict[tuple[str, float], FloatArray] = field(default_factory=dict)
    windows: dict[float, int] = field(default_factory=dict)
    delay_s: float = 0.0


def identify(paths: list[Path], robot: RobotData, *, velocity: str = 'dvl',
             fixed: tuple[int, ...] = (), predict: bool = True) -> Identification:
    """Fit the robot's hull terms to the recordings and evaluate them on the held-out parts.

    Raises:
        IdentifyError: A recording refused (one line naming it and what is missing), or no
            term excited.
    """
    if not paths:
        raise IdentifyError('no recording given')
    prior = robot.prior_theta()
    model = model_with_hull(robot, ZERO_HULL)
    training: list[Series] = []
    held_out: list[Series] = []
    knowns: list[FloatArray] = []
    phis: list[FloatArray] = []
    for path in paths:
        series = read_series(path, robot, velocity=velocity)
        if series.joints.shape[1] != model.n_joints:
            raise IdentifyError(f'{path}: {series.joints.shape[1]} joints recorded, robot '
                                f'{robot.name} has {model.n_joints}')
        cut = series.t_s[0] + (1.0 - HELD_OUT_FRACTION) * (series.t_s[-1] - series.t_s[0])
        for part in segments(series):
            if predict:
                parts = [(part.window(part.t_s < cut), training),
                         (part.window(part.t_s >= cut), held_out)]
            else:
                parts = [(part, training)]
            for piece, target in parts:
                if len(piece.t_s) >= 3:
                    target.append(piece)
        for train in training[len(knowns):]:
            knowns.append(known_forces(model, train.rpy, train.joints, train.nu,
                                       train.joint_rates, train.nu_dot,
                                       train.joint_accelerations))
            phis.append(hull_regressor(train.nu, train.nu_dot, train.gravity_body))
    if not knowns:
        raise IdentifyError('no stretch of the recordings has a measured velocity for '
                            f'{MIN_SEGMENT_S:g} s (the DVL never kept bottom lock)')
    phi = np.concatenate(phis)
    best: tuple[float, float, HullFit] | None = None
    for delay in DELAYS_S:
        y = np.concatenate([delayed(train, delay).tau - known
                            for train, known in zip(training, knowns, strict=True)])
        candidate = fit_hull(y, phi, prior, fixed)
        scale = np.sqrt(np.mean(y**2, axis=0))
        scale[scale == 0.0] = 1.0
        score = float(np.sum((candidate.residual_std / scale) ** 2))
        if best is None or score < best[0]:
            best = (score, delay, candidate)
    assert best is not None
    _, delay, fit = best
    result = Identification(robot, list(paths), fit, prior, training, held_out, delay_s=delay)
    if predict:
        excited = excited_axes(held_out)
        for horizon in HORIZONS_S:
            for name, theta, d in (('identified', fit.theta, delay), ('current', prior, 0.0)):
                inputs = [delayed(s, d) for s in held_out]
                errors = np.full(6, np.nan)
                total = 0
                for axis in range(6):
                    chosen = [s for s, a in zip(inputs, excited, strict=True) if a == axis]
                    per_axis, count = horizon_errors(model, theta, chosen or inputs, horizon)
                    errors[axis] = per_axis[axis]
                    total += count if chosen else 0
                result.errors[(name, horizon)] = errors
                result.windows[horizon] = total
    return result


def delayed(series: Series, delay_s: float) -> Series:
    """``series`` with the thrust wrench that acts at each sample: tau(t - delay_s)."""
    if delay_s == 0.0:
        return series
    shifted = copy.copy(series)
    shifted.tau = np.column_stack([np.interp(series.t_s - delay_s, series.t_s, column)
                                   for column in series.tau.T])
    return shifted


def excited_axes(series_list: list[Series]) -> list[int]:
    """Per series, the axis its thrusts excite most (RMS wrench over that of all series)."""
    if not series_list:
        return []
    overall = np.sqrt(np.mean(np.concatenate([s.tau for s in series_list]) ** 2, axis=0))
    overall[overall == 0.0] = 1.0
    return [int(np.argmax(np.sqrt(np.mean(s.tau**2, axis=0)) / overall)) for s in series_list]
