"""Benchmark of the controller and allocator steps: prints microseconds per call.

Run: ``.venv/bin/python bench/bench_control.py [--repeat N]``. Targets (issue 4): a
controller step at most 150 µs, an allocator step with thruster dynamics at most 50 µs. The
controller step is split into the UVMS model evaluations it needs (uvms_model: M, ζ, J,
J̇ q̇, forward kinematics) and the control law itself, so that it shows where the time goes.
Figures only: this script asserts nothing.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
for package in ('uvms_model', 'uvms_control'):
    sys.path.insert(0, str(ROOT / 'src' / package))

from uvms_control.core.allocation import AllocatorParameters, ThrusterAllocator  # noqa: E402
from uvms_control.core.fuzzy_switch import FuzzySwitch  # noqa: E402
from uvms_control.core.parameters import ControllerParameters  # noqa: E402
from uvms_control.core.task_space import task_space_model  # noqa: E402
from uvms_control.core.thruster_dynamics import ThrusterBank, ThrusterModelParameters  # noqa: E402
from uvms_control.core.unified_controller import UnifiedForceController  # noqa: E402
from uvms_model.thrusters import ThrusterLayout  # noqa: E402

from uvms_model import UvmsModel  # noqa: E402

Q = np.array([0.01, -0.02, 0.03, 0.02, -0.01, 0.05, 0.02, 0.48, -1.5])
W = np.array([0.02, 0.01, -0.01, 0.01, 0.02, -0.01, 0.05, -0.03, 0.04])
#: Normal contact force (N, along map_ned +x) in the three regimes of the fuzzy switch.
NORMAL_FORCES = {
    'free motion, no rule fires': 0.0,
    'transition, FM and FL fire': 105.0,
    'constrained, FL and VS fire': 150.0,
}


def time_us(function: Callable[[], object], repeat: int, rounds: int = 5) -> tuple[float, float]:
    """Median and best of `rounds` averages over `repeat` calls, in microseconds."""
    function()
    averages = []
    for _ in range(rounds):
        start = time.perf_counter()
        for _ in range(repeat):
            function()
        averages.append((time.perf_counter() - start) / repeat * 1e6)
    return statistics.median(averages), min(averages)


def main() -> None:
    """Time the hot paths and print a table."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--repeat', type=int, default=2000, help='calls per round (default 2000)')
    repeat = parser.parse_args().repeat

    model = UvmsModel()
    steps = []
    rot_ned_from_ee = model.ee_rotation(Q)
    for regime, normal_force in NORMAL_FORCES.items():
        force = rot_ned_from_ee.T @ np.array([normal_force, 0.0, 0.0])
        controller = UnifiedForceController(ControllerParameters.from_flat_dict(), model)
        t = [0.0]

        def controller_step(c=controller, t=t, f=force) -> None:  # type: ignore[no-untyped-def]
            t[0] += 0.002
            c.step_from_sensors(t[0], Q, W, f)

        steps.append((f'controller step, {regime}', controller_step, 150.0))

    q_dot = model.velocity_transform(Q) @ W
    x_ee = model.ee_position(Q)

    def model_evaluations() -> None:
        model.velocity_transform(Q)
        model.ee_position(Q)
        model.ee_rotation(Q)
        model.mass_matrix(Q)
        model.bias(Q, q_dot)
        model.ee_jacobian(Q)
        model.ee_jacobian_dot_qdot(Q, q_dot)

    layout = ThrusterLayout.from_parameters()
    allocator = ThrusterAllocator(
        AllocatorParameters(layout.thrust_matrix(), layout.max_thrust_n, np.full(3, 200.0))
    )
    tau_b = np.array([60.0, -20.0, 30.0, 4.0, -6.0, 8.0, 10.0, 20.0, -5.0])
    bank = ThrusterBank(ThrusterModelParameters(), layout.count)
    f_td = allocator.allocate(tau_b).thrust
    switch = FuzzySwitch()

    rows = [
        *steps,
        ('  of which UVMS model evaluations (uvms_model)', model_evaluations, None),
        (
            '  task-space model M~, zeta~ (eq. 27-28)',
            lambda: task_space_model(model, Q, q_dot, x_ee),
            None,
        ),
        ('  fuzzy switch W, two rules firing', lambda: switch.weight(0.7, 0.0), None),
        (
            'allocator step at 500 Hz (eq. 10 + thruster dynamics, 2 ms)',
            lambda: allocator.step(tau_b, 0.002),
            50.0,
        ),
        ('allocator step at 1 kHz (1 ms)', lambda: allocator.step(tau_b, 0.001), 50.0),
        (
            '  of which allocation with saturation (eq. 10)',
            lambda: allocator.allocate(tau_b),
            None,
        ),
        ('  of which thruster dynamics, 8 thrusters, 1 ms', lambda: bank.step(f_td, 0.001), None),
    ]
    print(f'{"hot path":62s} {"median µs":>10s} {"best µs":>9s} {"target µs":>10s}')
    results = {}
    for label, function, target in rows:
        median, best = time_us(function, repeat)
        results[label] = median
        target_text = f'{target:.0f}' if target is not None else ''
        print(f'{label:62s} {median:10.1f} {best:9.1f} {target_text:>10s}')
    model_part = results[rows[3][0]]
    for label, _, _ in steps:
        law = results[label] - model_part
        print(f'{label}: control law without the model evaluations {law:.1f} µs')


if __name__ == '__main__':
    main()
