"""Step response of the stack's T200 thruster model beside von Benzon's identified one.

Usage: ``.venv/bin/python tools/t200_step_response.py [--step N ...] [--plot FILE.png]``

The stack's thruster model (Healey et al. 1995, paper eq. 11-15, ``ThrusterBank`` of
``uvms_thrusters.thruster_dynamics``) runs with the constants of
``robots/bluerov2_alpha5/thrusters.yaml`` from rest under a step of the desired thrust. Beside
it, von Benzon et al. 2022 (J. Mar. Sci. Eng. 10, 1898) identified the T200's thrust dynamics
as the unit-gain transfer function

    K(s) = (6136 s + 108700) / (s^3 + 89 s^2 + 9258 s + 108700)

(poles -13.16 and -37.9 ± 82.6j, zero -17.7). Both responses are normalized by their final
value (the model's steady thrust equals the command below the current limit) and compared:
rise time 10-90 %, time to 63 %, settling time (2 % band), overshoot, and the RMS difference
of the normalized responses over the window. It also prints the static thrust the current
limit allows, forward and reverse, against the 16 V data sheet (51.4 N, 39.9 N).
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt
import yaml
from scipy import signal

REPO = Path(__file__).resolve().parent.parent
for _package in ('uvms_control', 'uvms_thrusters', 'uvms_model'):
    _source = REPO / 'src' / _package
    if str(_source) not in sys.path:
        sys.path.insert(0, str(_source))

from uvms_thrusters.parameters import thruster_parameters_from_flat_dict  # noqa: E402
from uvms_thrusters.thruster_dynamics import ThrusterBank, ThrusterModelParameters  # noqa: E402

FloatArray = npt.NDArray[np.float64]

ROBOT_DIRECTORY = REPO / 'src' / 'uvms_description' / 'robots' / 'bluerov2_alpha5'
THRUSTERS_FILE = ROBOT_DIRECTORY / 'thrusters.yaml'
VON_BENZON_NUMERATOR = (6136.0, 108700.0)
VON_BENZON_DENOMINATOR = (1.0, 89.0, 9258.0, 108700.0)
#: Blue Robotics T200 at 16 V: the extremes of the public performance data (N).
DATASHEET_FORWARD_N = 51.4
DATASHEET_REVERSE_N = 39.9
#: Sea water, as config/robot.yaml's hydrodynamics.water_density_kg_m3 (kg/m^3).
WATER_DENSITY = 1025.0


@dataclass(frozen=True)
class StepMetrics:
    """Figures of a normalized step response (final value 1).

    Attributes:
        rise_time_s: time from 10 % to 90 % of the final value (s).
        time_to_63_s: first time at 63.2 % (s), the time constant of a first-order lag.
        settling_time_s: last time outside the ±2 % band (s).
        overshoot: peak above the final value, a fraction of it (-).
    """

    rise_time_s: float
    time_to_63_s: float
    settling_time_s: float
    overshoot: float


def load_thruster_parameters(
    path: Path = THRUSTERS_FILE, water_density: float = WATER_DENSITY
) -> ThrusterModelParameters:
    """The ``thruster.*`` constants of a robot's thrusters.yaml (the allocator's section)."""
    document = yaml.safe_load(path.read_text(encoding='utf-8'))
    group = document['/**/thruster_allocator']['ros__parameters']['thruster']
    flat = {f'thruster.{key}': value for key, value in group.items()}
    return thruster_parameters_from_flat_dict(flat, water_density)


def model_step_response(
    params: ThrusterModelParameters, command_n: float, duration_s: float, dt: float = 1e-4
) -> tuple[FloatArray, FloatArray]:
    """Thrust (N) of one thruster from rest under a step of the desired thrust to command_n.

    Returns:
        (t, thrust): sample times from 0 to duration_s (s) and the actual thrust (N).
    """
    bank = ThrusterBank(params, 1)
    steps = round(duration_s / dt)
    t = np.arange(steps + 1) * dt
    thrust = np.zeros(steps + 1)
    command = np.array([command_n])
    for k in range(1, steps + 1):
        thrust[k] = bank.step(command, dt)[0]
    return t, thrust


def reference_step_response(t: FloatArray) -> FloatArray:
    """Unit step response of von Benzon's K(s) at the times t (s)."""
    system = signal.lti(VON_BENZON_NUMERATOR, VON_BENZON_DENOMINATOR)
    _, y = signal.step(system, T=t)
    return np.asarray(y, dtype=np.float64)


def step_metrics(t: FloatArray, y: FloatArray) -> StepMetrics:
    """Rise time, time to 63 %, 2 % settling time and overshoot of a response with final 1."""

    def first_crossing(level: float) -> float:
        index = int(np.argmax(y >= level))
        if y[index] < level:
            return float('nan')
        if index == 0:
            return float(t[0])
        # Linear interpolation between the samples around the crossing.
        y0, y1 = y[index - 1], y[index]
        return float(t[index - 1] + (level - y0) / (y1 - y0) * (t[index] - t[index - 1]))

    outside = np.nonzero(np.abs(y - 1.0) > 0.02)[0]
    settling = float(t[min(outside[-1] + 1, t.size - 1)]) if outside.size else float(t[0])
    return StepMetrics(
        rise_time_s=first_crossing(0.9) - first_crossing(0.1),
        time_to_63_s=first_crossing(1.0 - np.exp(-1.0)),
        settling_time_s=settling,
        overshoot=max(0.0, float(np.max(y)) - 1.0),
    )


def static_thrust_limits(params: ThrusterModelParameters) -> tuple[float, float]:
    """Largest steady bollard thrust (N) the current limit holds: (forward, reverse magnitude)."""
    bank = ThrusterBank(params, 1)
    return bank.max_steady_thrust(forward=True), bank.max_steady_thrust(forward=False)


@dataclass(frozen=True)
class Comparison:
    """The model's and von Benzon's normalized step responses and their figures."""

    command_n: float
    t: FloatArray
    model: FloatArray
    reference: FloatArray
    model_metrics: StepMetrics
    reference_metrics: StepMetrics
    rms_difference: float


def compare(params: ThrusterModelParameters, command_n: float, duration_s: float = 0.6
            ) -> Comparison:
    """Step of command_n (N) through the model beside K(s), both normalized to final value 1.

    The model's response is normalized by the command (its steady thrust below the current
    limit); a command beyond the limit is refused, since it has no linear counterpart.
    """
    forward, reverse = static_thrust_limits(params)
    limit = forward if command_n >= 0.0 else reverse
    if command_n == 0.0 or abs(command_n) > limit:
        msg = f'step {command_n} N must be non-zero and within the current limit {limit:.1f} N'
        raise ValueError(msg)
    t, thrust = model_step_response(params, command_n, duration_s)
    model = thrust / command_n
    reference = reference_step_response(t)
    return Comparison(
        command_n=command_n,
        t=t,
        model=model,
        reference=reference,
        model_metrics=step_metrics(t, model),
        reference_metrics=step_metrics(t, reference),
        rms_difference=float(np.sqrt(np.mean((model - reference) ** 2))),
    )


def _report(comparisons: list[Comparison], params: ThrusterModelParameters) -> str:
    forward, reverse = static_thrust_limits(params)
    lines = [
        'T200 static thrust at the current limit (bollard, steady):',
        f'  forward {forward:6.2f} N   data sheet {DATASHEET_FORWARD_N} N   '
        f'({100.0 * (forward / DATASHEET_FORWARD_N - 1.0):+.1f} %)',
        f'  reverse {reverse:6.2f} N   data sheet {DATASHEET_REVERSE_N} N   '
        f'({100.0 * (reverse / DATASHEET_REVERSE_N - 1.0):+.1f} %)',
        '',
        'Step response, normalized by the final value:',
        f'  {"":24s} {"rise 10-90":>11s} {"t63":>8s} {"settle 2%":>10s} {"overshoot":>10s}',
    ]
    reference_done = False
    for c in comparisons:
        rows = [(f'model, step {c.command_n:+.1f} N', c.model_metrics)]
        if not reference_done:
            rows.insert(0, ('von Benzon K(s)', c.reference_metrics))
            reference_done = True
        for label, m in rows:
            lines.append(
                f'  {label:24s} {m.rise_time_s:9.4f} s {m.time_to_63_s:6.4f} s '
                f'{m.settling_time_s:8.4f} s {100.0 * m.overshoot:8.1f} %'
            )
        lines.append(f'  {"":24s} RMS difference of the normalized responses over '
                     f'{c.t[-1]:.1f} s: {c.rms_difference:.4f}')
    return '\n'.join(lines)


def _plot(comparisons: list[Comparison], path: Path) -> None:
    import matplotlib

    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    ax.plot(comparisons[0].t, comparisons[0].reference, 'k--', label='von Benzon K(s)')
    for c in comparisons:
        ax.plot(c.t, c.model, label=f'Healey model, step {c.command_n:+.1f} N')
    ax.set_xlabel('time (s)')
    ax.set_ylabel('thrust / final thrust (-)')
    ax.set_title('T200 step response')
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main(argv: list[str] | None = None) -> int:
    """Print the comparison; with --plot, also draw it to a PNG."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--thrusters', type=Path, default=THRUSTERS_FILE,
                        help='a robot thrusters.yaml (default: bluerov2_alpha5)')
    parser.add_argument('--step', type=float, nargs='+', default=[10.0, 25.0, -25.0],
                        help='desired thrust steps from rest (N)')
    parser.add_argument('--duration', type=float, default=0.6, help='window (s)')
    parser.add_argument('--water-density', type=float, default=WATER_DENSITY,
                        help='rho (kg/m^3)')
    parser.add_argument('--plot', type=Path, help='write the responses to this PNG')
    args = parser.parse_args(argv)
    params = load_thruster_parameters(args.thrusters, args.water_density)
    comparisons = [compare(params, step, args.duration) for step in args.step]
    print(_report(comparisons, params))
    if args.plot is not None:
        _plot(comparisons, args.plot)
        print(f'plot: {args.plot}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
