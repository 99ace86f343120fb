"""The identification's pipeline: recordings -> series -> known terms -> fit -> predictions."""

from __future__ import annotations

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
    """

    robot: RobotData
    recordings: list[Path]
    fit: HullFit
    prior: FloatArray
    training: list[Series]
    held_out: list[Series]
    errors: dict[tuple[str, float], FloatArray] = field(default_factory=dict)
    windows: dict[float, int] = field(default_factory=dict)


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
    ys, phis = [], []
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
        for train in training[len(ys):]:
            known = known_forces(model, train.rpy, train.joints, train.nu, train.joint_rates,
                                 train.nu_dot, train.joint_accelerations)
            ys.append(train.tau - known)
            phis.append(hull_regressor(train.nu, train.nu_dot, train.gravity_body))
    if not ys:
        raise IdentifyError('no stretch of the recordings has a measured velocity for '
                            f'{MIN_SEGMENT_S:g} s (the DVL never kept bottom lock)')
    fit = fit_hull(np.concatenate(ys), np.concatenate(phis), prior, fixed)
    result = Identification(robot, list(paths), fit, prior, training, held_out)
    if predict:
        excited = excited_axes(held_out)
        for horizon in HORIZONS_S:
            for name, theta in (('identified', fit.theta), ('current', prior)):
                errors = np.full(6, np.nan)
                total = 0
                for axis in range(6):
                    chosen = [s for s, a in zip(held_out, excited, strict=True) if a == axis]
                    per_axis, count = horizon_errors(model, theta, chosen or held_out,
                                                     horizon)
                    errors[axis] = per_axis[axis]
                    total += count if chosen else 0
                result.errors[(name, horizon)] = errors
                result.windows[horizon] = total
    return result


def excited_axes(series_list: list[Series]) -> list[int]:
    """Per series, the axis its thrusts excite most (RMS wrench over that of all series)."""
    if not series_list:
        return []
    overall = np.sqrt(np.mean(np.concatenate([s.tau for s in series_list]) ** 2, axis=0))
    overall[overall == 0.0] = 1.0
    return [int(np.argmax(np.sqrt(np.mean(s.tau**2, axis=0)) / overall)) for s in series_list]
