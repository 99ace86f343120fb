"""Benchmark of the controller and allocator steps: microseconds per call, new and previous.

Run: ``.venv/bin/python bench/bench_control.py [--repeat N]``. Each row times the current
code (the controller on the Pinocchio model of the URDF) and, in the same run, the previous
implementation: the same control law on the previous pure-Python model
(``test/unit/model/reference_model.py``, evaluated by the separate calls the controller made
before one-pass ``task_space_terms``), and their ratio. The allocator rows have no previous
implementation here (its hot path was compiled too, into Numba kernels, commit 6daedcb; the
interpreted code it replaced is not kept), so they are timed once, the current code only.
Targets (issue 10): a controller step at most 40 µs; an allocator step with
thruster dynamics at most 50 µs (issue 4). Figures only: this script asserts nothing.
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
for folder in ('src/uvms_description', 'src/uvms_model', 'src/uvms_control', 'src/uvms_thrusters',
               'test/unit/model'):
    sys.path.insert(0, str(ROOT / folder))

from reference_model import ReferenceModel  # noqa: E402
from uvms_control.core.law.fuzzy_switch import FuzzySwitch  # noqa: E402
from uvms_control.core.law.task_space import task_space_model_from_terms  # noqa: E402
from uvms_control.core.law.unified_controller import UnifiedForceController  # noqa: E402
from uvms_control.core.parameters import ControllerParameters  # noqa: E402
from uvms_model.thrusters import ThrusterLayout  # noqa: E402
from uvms_thrusters.allocation import AllocatorParameters, ThrusterAllocator  # noqa: E402
from uvms_thrusters.thruster_dynamics import ThrusterBank, ThrusterModelParameters  # noqa: E402

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

    model, previous = UvmsModel(), ReferenceModel()
    rows: list[tuple[str, Callable[[], object], Callable[[], object] | None, float | None]] = []
    rot_ned_from_ee = model.ee_rotation(Q)
    for regime, normal_force in NORMAL_FORCES.items():
        force = rot_ned_from_ee.T @ np.array([normal_force, 0.0, 0.0])
        steps = []
        for m in (model, previous):
            params = ControllerParameters.from_flat_dict()
            controller = UnifiedForceController(params, m)  # type: ignore[arg-type]
            t = [0.0]

            def controller_step(c=controller, t=t, f=force) -> None:  # type: ignore[no-untyped-def]
                t[0] += 0.002
                c.step_from_sensors(t[0], Q, W, f)

            steps.append(controller_step)
        rows.append((f'controller step, {regime}', steps[0], steps[1], 40.0))

    q_dot = model.velocity_transform(Q) @ W
    terms = model.task_space_terms(Q, w=W)
    rows.append(
        (
            '  of which the model: X, J, J_dot q_dot, M, zeta, B',
            lambda: model.task_space_terms(Q, w=W),
            lambda: previous.task_space_terms(Q, w=W),
            None,
        )
    )
    rows.append(
        (
            '  of which M~, zeta~, J+ (eq. 24-28)',
            lambda: task_space_model_from_terms(terms),
            None,
            None,
        )
    )
    switch = FuzzySwitch()
    rows.append(
        ('  of which the fuzzy switch W (two rules)', lambda: switch.weight(0.7, 0.0), None, None)
    )

    layout = ThrusterLayout.from_parameters()
    allocator = ThrusterAllocator(
        AllocatorParameters(layout.thrust_matrix(), layout.max_thrust_n, np.full(3, 200.0))
    )
    tau_b = np.array([60.0, -20.0, 30.0, 4.0, -6.0, 8.0, 10.0, 20.0, -5.0])
    bank = ThrusterBank(ThrusterModelParameters(), layout.count)
    f_td = allocator.allocate(tau_b).thrust
    rows += [
        (
            'allocator step at 500 Hz (eq. 10 + thruster dynamics, 2 ms)',
            lambda: allocator.step(tau_b, 0.002),
            None,
            50.0,
        ),
        ('allocator step at 1 kHz (1 ms)', lambda: allocator.step(tau_b, 0.001), None, 50.0),
        ('  of which allocation (eq. 10)', lambda: allocator.allocate(tau_b), None, None),
        ('  of which thruster dynamics, 8 thrusters', lambda: bank.step(f_td, 0.001), None, None),
    ]
    del q_dot
    print(
        f'{"hot path (median of 5 rounds, µs per call)":62s} {"now":>8s} {"previous":>9s} '
        f'{"speed-up":>9s} {"target":>7s}'
    )
    for label, function, previous_function, target in rows:
        now, _ = time_us(function, repeat)
        before = time_us(previous_function, max(repeat // 4, 1))[0] if previous_function else None
        before_text = f'{before:9.1f}' if before is not None else f'{"":9s}'
        ratio_text = f'{before / now:8.2f}x' if before is not None else f'{"":9s}'
        target_text = f'{target:.0f}' if target is not None else ''
        print(f'{label:62s} {now:8.1f} {before_text} {ratio_text} {target_text:>7s}')


if __name__ == '__main__':
    main()
