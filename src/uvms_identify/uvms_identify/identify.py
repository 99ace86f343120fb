"""The identification's pipeline: recordings -> series -> known terms -> fit -> predictions."""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from uvms_identify.actuators import (
    Term,
    ThrustPath,
    checked_gain,
    fit_joint_friction,
    search_thrust_path,
)
from uvms_identify.errors import IdentifyError
from uvms_identify.fit import HullFit, fit_hull
from uvms_identify.known_terms import ZERO_HULL, known_forces, model_with_hull
from uvms_identify.predict import horizon_errors
from uvms_identify.recording import MIN_SEGMENT_S, Series, gaps_text, read_series, segments
from uvms_identify.regressor import hull_regressor
from uvms_identify.robot_data import RobotData

FloatArray = NDArray[np.float64]

#: Fraction of each recording held out (its end) for the prediction figures.
HELD_OUT_FRACTION = 0.3
HORIZONS_S = (1.0, 10.0)
#: Delays searched between the recorded thrusts and the force they make (s): the thruster's
#: lag and the command's transport, as one delay (the recorded thrust at t acts at t + d).
DELAYS_S = tuple(round(float(d), 3) for d in np.arange(-0.04, 0.0801, 0.005))
#: The rows of the thrust gain's check: the gain from them alone must agree with the gain
#: from all rows (``uvms_identify.actuators.checked_gain``).
TRANSLATION_AXES = (0, 1, 2)


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
        thrust: The thrusts' gain, lag and delay (``uvms_identify.actuators``).
        joint_friction: Per arm joint, viscous and Coulomb friction (empty without joint
            torques recorded).
        joint_names: The arm's joints, in the model's order.
        gaps_s: Per signal, the time of the recordings in its gaps (s): left out of the fit
            with the smoothing window around each (``uvms_identify.recording``).
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
    thrust: ThrustPath | None = None
    joint_friction: list[Term] = field(default_factory=list)
    joint_names: list[str] = field(default_factory=list)
    gaps_s: dict[str, float] = field(default_factory=dict)


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
    arm_knowns: list[FloatArray] = []
    phis: list[FloatArray] = []
    gaps_s: dict[str, float] = {}
    for path in paths:
        series = read_series(path, robot, velocity=velocity)
        for what, seconds in series.gaps_s.items():
            gaps_s[what] = gaps_s.get(what, 0.0) + seconds
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
            everything = known_forces(model, train.rpy, train.joints, train.nu,
                                      train.joint_rates, train.nu_dot,
                                      train.joint_accelerations, slice(0, None))
            knowns.append(everything[:, :6])
            arm_knowns.append(everything[:, 6:])
            phis.append(hull_regressor(train.nu, train.nu_dot, train.gravity_body))
    if not knowns:
        raise IdentifyError('no stretch of the recordings has every signal measured for '
                            f'{MIN_SEGMENT_S:g} s (time in gaps: {gaps_text(gaps_s)}; a DVL '
                            'without bottom lock, or messages lost on the way to the '
                            'recording)')
    phi = np.concatenate(phis)
    known_all = np.concatenate(knowns)
    # Rows weighted as the hull's fit weighs them (its residual per axis at the recorded
    # thrusts), then the thrusts' gain, lag and delay that fit best, then the hull's terms.
    first = fit_hull(np.concatenate([s.tau for s in training]) - known_all, phi, prior, fixed)
    sigma = first.residual_std.copy()
    sigma[sigma == 0.0] = 1.0
    times, wrenches = [s.t_s for s in training], [s.tau for s in training]
    thrust = search_thrust_path(times, wrenches, knowns, phi, 1.0 / sigma, DELAYS_S)
    translation = np.where(np.isin(np.arange(6), TRANSLATION_AXES), 1.0 / sigma, 0.0)
    thrust = checked_gain(thrust, search_thrust_path(
        times, wrenches, knowns, phi, translation, (thrust.delay_s,),
        (thrust.time_constant.value,)).gain)
    if not thrust.gain.identified:
        # The lag and delay again with the gain held at its prior: a gain the data cannot
        # tell must not choose them (it moved the delay by 5 ms, surge added mass by 5 %).
        thrust = search_thrust_path(times, wrenches, knowns, phi, 1.0 / sigma, DELAYS_S,
                                    gain=thrust.gain)
    if not thrust.gain.identified and not thrust.time_constant.identified:
        # Thrusts as recorded but for the delay: chosen by the bounded fit itself (the
        # projections' unconstrained score moved it by 5 ms on the acceptance recordings,
        # the surge added mass by 2 %).
        thrust = ThrustPath(thrust.gain, thrust.time_constant,
                            bounded_delay(training, knowns, phi, prior, fixed), thrust.weights)
    y = np.concatenate([thrust.wrench(s.t_s, s.tau) for s in training]) - known_all
    fit = fit_hull(y, phi, prior, fixed)
    names = list(model.joint_names)
    friction: list[Term] = []
    if all(s.joint_torques.shape[1] == model.n_joints for s in training) and model.n_joints:
        friction = fit_joint_friction(
            np.concatenate([s.joint_rates for s in training]),
            np.concatenate([s.joint_torques for s in training]) - np.concatenate(arm_knowns),
            names)
    result = Identification(robot, list(paths), fit, prior, training, held_out,
                            delay_s=thrust.delay_s, thrust=thrust, joint_friction=friction,
                            joint_names=names, gaps_s=gaps_s)
    if predict:
        excited = excited_axes(held_out)
        for horizon in HORIZONS_S:
            for name, theta, thrust_path in (('identified', fit.theta, thrust),
                                      ('current', prior, None)):
                inputs = [driven(s, thrust_path) for s in held_out]
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


def bounded_delay(training: list[Series], knowns: list[FloatArray], phi: FloatArray,
                  prior: FloatArray, fixed: tuple[int, ...]) -> float:
    """The delay of ``DELAYS_S`` whose bounded hull fit leaves the least normalized residual."""
    best: tuple[float, float] | None = None
    for delay in DELAYS_S:
        y = np.concatenate([delayed(train, delay).tau - known
                            for train, known in zip(training, knowns, strict=True)])
        candidate = fit_hull(y, phi, prior, fixed)
        scale = np.sqrt(np.mean(y**2, axis=0))
        scale[scale == 0.0] = 1.0
        score = float(np.sum((candidate.residual_std / scale) ** 2))
        if best is None or score < best[0]:
            best = (score, delay)
    assert best is not None
    return best[1]


def driven(series: Series, path: ThrustPath | None) -> Series:
    """``series`` with the wrench its thrusts make through ``path`` (None: as recorded)."""
    if path is None:
        return series
    shifted = copy.copy(series)
    shifted.tau = path.wrench(series.t_s, series.tau)
    return shifted


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
