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
from uvms_identify.recording import Series, read_series
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


def split(series: Series, fraction: float = HELD_OUT_FRACTION) -> tuple[Series, Series]:
    """The first (1 - fraction) of a series, and its end."""
    cut = series.t_s[0] + (1.0 - fraction) * (series.t_s[-1] - series.t_s[0])
    return series.window(series.t_s < cut), series.window(series.t_s >= cut)


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
        train, rest = split(series) if predict else (series, series.window(series.t_s < 0))
        training.append(train)
        held_out.append(rest)
        known = known_forces(model, train.rpy, train.joints, train.nu, train.joint_rates,
                             train.nu_dot, train.joint_accelerations)
        ys.append(train.tau - known)
        phis.append(hull_regressor(train.nu, train.nu_dot, train.gravity_body))
    fit = fit_hull(np.concatenate(ys), np.concatenate(phis), prior, fixed)
    result = Identification(robot, list(paths), fit, prior, training, held_out)
    if predict:
        for horizon in HORIZONS_S:
            for name, theta in (('identified', fit.theta), ('current', prior)):
                errors, count = horizon_errors(model, theta, held_out, horizon)
                result.errors[(name, horizon)] = errors
                result.windows[horizon] = count
    return result
