"""Per-call times of the UVMS model (Pinocchio + Numba kernels) against the previous one.

Run: ``.venv/bin/python bench/bench_model.py [--repeat N]``. For each call it prints the best
of several rounds (microseconds per call) of ``uvms_model.UvmsModel`` and of the previous
pure-Python implementation (``test/unit/model/reference_model.py``, the tests' oracle), in
the same run, and their ratio: mass matrix, bias, forward dynamics, one RK4 step, the
controller's model set, one controller step (the same control law on either model) and one
allocator step (the previous numpy allocator, ``test/unit/thrusters/reference_allocator.py``);
then Pinocchio's plain ABA for scale. Targets (issue 10): an RK4 step of the full model and a
controller step at most 40 us each. The machine is shared: figures move with its load,
ratios much less. A benchmark prints figures; it never asserts on time.
"""

from __future__ import annotations

import argparse
import platform
import sys
import timeit
from collections.abc import Callable
from pathlib import Path

import numba
import numpy as np
import pinocchio as pin

ROOT = Path(__file__).resolve().parents[1]
for folder in ('src/uvms_description', 'src/uvms_model', 'src/uvms_control', 'src/uvms_thrusters',
               'test/unit/model',
               'test/unit/control', 'test/unit/thrusters'):
    sys.path.insert(0, str(ROOT / folder))

from reference_allocator import ReferenceAllocator  # noqa: E402
from reference_model import ReferenceModel  # noqa: E402
from uvms_control.core.law.unified_controller import UnifiedForceController  # noqa: E402
from uvms_control.core.parameter_specs import CONTROLLER_PARAMETER_SPECS  # noqa: E402
from uvms_control.core.parameters import ControllerParameters  # noqa: E402
from uvms_model.thrusters import ThrusterLayout  # noqa: E402
from uvms_thrusters.allocation import AllocatorParameters, ThrusterAllocator  # noqa: E402

from uvms_description.robots import (  # noqa: E402
    RobotFolderError,
    robot_files,
    robot_names,
    robot_parameters,
    with_description_paths,
)
from uvms_model import UvmsModel, UvmsParameters  # noqa: E402

TARGET_STEP_US = 40.0


def per_call_us(func: Callable[[], object], number: int, repeat: int) -> float:
    """Best time per call over ``repeat`` rounds of ``number`` calls, in microseconds."""
    times = timeit.repeat(func, number=number, repeat=repeat)
    return min(times) / number * 1e6


def main() -> None:
    """Time the model's calls, new and previous, and print a table."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument('--repeat', type=int, default=20, help='rounds per figure (best kept)')
    parser.add_argument('--number', type=int, default=300, help='calls per round')
    args = parser.parse_args()

    params = UvmsParameters()
    model, previous = UvmsModel(params), ReferenceModel(params)
    rng = np.random.default_rng(0)
    q = np.concatenate((rng.uniform(-1, 1, 3), [0.1, -0.2, 0.7], [0.0, 0.93, -1.57]))
    w = rng.normal(0.0, 0.3, 9)
    tau_b = rng.normal(0.0, 20.0, 9)
    f_ee = np.array([-150.0, 0.0, 5.0])
    q_dot = model.velocity_transform(q) @ w
    dt = 1e-3
    # Two states with different joint angles: alternating defeats the previous model's
    # per-configuration cache, as the stages of an RK4 step or successive steps do.
    states = [q, q + np.concatenate((np.zeros(6), [0.01, -0.02, 0.03]))]
    counter = [0]

    def alternate() -> np.ndarray:
        counter[0] ^= 1
        return states[counter[0]]

    f_sensor = model.ee_rotation(q).T @ np.array([105.0, 0.0, 0.0])  # fuzzy hand-over

    def controller_step(m: UvmsModel | ReferenceModel) -> Callable[[], object]:
        controller = UnifiedForceController(ControllerParameters.from_flat_dict(), m)  # type: ignore[arg-type]
        clock = [0.0]

        def step() -> object:
            clock[0] += 0.002
            return controller.step_from_sensors(clock[0], q, w, f_sensor)

        return step

    layout = ThrusterLayout.from_parameters()
    limits = AllocatorParameters(layout.thrust_matrix(), layout.max_thrust_n, np.full(3, 200.0))

    def calls(
        m: UvmsModel | ReferenceModel, allocator: ThrusterAllocator | ReferenceAllocator
    ) -> list[tuple[str, Callable[[], object]]]:
        return [
            ('mass matrix M_b(q) (eq. 8)', lambda: m.mass_matrix_body(alternate())),
            ('bias C_b w + D_b w + G_b (eq. 8)', lambda: m.bias_body(alternate(), w)),
            ('forward dynamics w_dot', lambda: m.forward_dynamics(alternate(), w, tau_b, f_ee)),
            ('one RK4 step of the full model', lambda: m.step(q, w, tau_b, f_ee, dt)),
            (
                'one semi-implicit Euler step',
                lambda: m.step(alternate(), w, tau_b, f_ee, dt, method='semi_implicit_euler'),
            ),
            (
                "controller's set: X, J, J_dot q_dot, M, zeta, B",
                lambda: m.task_space_terms(alternate(), q_dot),
            ),
            ('one controller step (eq. 2, 22-39)', controller_step(m)),
            ('one allocator step (eq. 10-15)', lambda: allocator.step(tau_b, 2e-3)),
        ]

    print(
        f'uvms_model benchmark: Python {platform.python_version()}, numpy {np.__version__}, '
        f'Pinocchio {pin.__version__}, Numba {numba.__version__}, {platform.machine()}; '
        f'best of {args.repeat} x {args.number} calls (previous: 1/5 of the calls)'
    )
    print(f'  {"call":<48s} {"now":>10s} {"previous":>10s} {"speed-up":>9s}')
    results: dict[str, float] = {}
    for (name, new_call), (_, old_call) in zip(
        calls(model, ThrusterAllocator(limits)), calls(previous, ReferenceAllocator(limits)),
        strict=True,
    ):
        new_us = per_call_us(new_call, args.number, args.repeat)
        old_us = per_call_us(old_call, max(args.number // 5, 1), args.repeat)
        results[name] = new_us
        print(f'  {name:<48s} {new_us:8.1f} us {old_us:8.1f} us {old_us / new_us:8.2f}x')

    rigid = model.dynamics.model  # the rigid bodies with the added-mass sliders, for scale
    data = rigid.createData()
    config, velocity = pin.neutral(rigid), np.zeros(rigid.nv)
    torque = np.zeros(rigid.nv)
    aba_us = per_call_us(
        lambda: pin.aba(rigid, data, config, velocity, torque), args.number, args.repeat
    )
    label = f'Pinocchio aba alone ({rigid.njoints - 1} joints, C++)'
    print(f'  {label:<48s} {aba_us:8.1f} us')
    for name in ('one RK4 step of the full model', 'one controller step (eq. 2, 22-39)'):
        step_us = results[name]
        verdict = 'met' if step_us <= TARGET_STEP_US else 'MISSED'
        print(f'  {name}: {step_us:.1f} us, target {TARGET_STEP_US:.0f} us {verdict}')
    robot_figures(args.number, args.repeat)


def robot_figures(number: int, repeat: int) -> None:
    """RK4 step and controller step of every robot folder (its own URDF, files and gains)."""
    print('per robot (uvms_description robots/): RK4 step, controller step')
    for name in robot_names():
        try:
            robot_files(name)
        except RobotFolderError as exc:
            print(f'  {name:<20s} skipped: {exc}')
            continue
        model, step, control = _robot_calls(name)
        rk4_us = per_call_us(step, number, repeat)
        control_us = per_call_us(control, number, repeat)
        print(f'  {name:<20s} n = {model.n_joints}: RK4 step {rk4_us:8.1f} us, '
              f'controller step {control_us:8.1f} us')


def _robot_calls(name: str) -> tuple[UvmsModel, Callable[[], object], Callable[[], object]]:
    """A robot's model, one RK4 step and one controller step on it (gains of its files)."""
    values = {k: item.value for k, item in robot_parameters(name, 'controller').items()}
    model_values = with_description_paths(
        {k: v for k, v in values.items() if k.split('.')[0] in ('thrusters', 'sensor')}, name)
    model = UvmsModel(UvmsParameters.from_flat_dict(model_values))
    gains = {spec.name for spec in CONTROLLER_PARAMETER_SPECS}
    controller = UnifiedForceController(ControllerParameters.from_flat_dict(
        {k: v for k, v in values.items() if k in gains}), model)
    q = np.zeros(model.n_dof)
    w = np.full(model.n_dof, 0.05)
    tau_b = np.full(model.n_dof, 1.0)
    clock = [0.0]

    def control() -> object:
        clock[0] += 0.002
        return controller.step_from_sensors(clock[0], q, w, np.zeros(3))

    return model, lambda: model.step(q, w, tau_b, None, 1e-3), control


if __name__ == '__main__':
    main()
