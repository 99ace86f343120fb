"""Per-call times of the UVMS model (uvms_model) next to Pinocchio's ABA on the same rigid bodies.

Run: ``.venv/bin/python bench/bench_model.py [--repeat N]``. Prints the best of several
rounds (microseconds per call), the target for one RK4 step (200 us, stretch 100 us), and the
ratio to Pinocchio's ABA (C++) for the rigid bodies alone. A benchmark prints figures; it
never asserts on time.
"""

from __future__ import annotations

import argparse
import platform
import timeit
from collections.abc import Callable

import numpy as np
from uvms_model.hydrodynamics import cylinder_inertia
from uvms_model.kinematics import rot_ned_from_body

from uvms_model import UvmsModel, UvmsParameters

TARGET_STEP_US = 200.0
STRETCH_STEP_US = 100.0


def per_call_us(func: Callable[[], object], number: int, repeat: int) -> float:
    """Best time per call over ``repeat`` rounds of ``number`` calls, in microseconds."""
    times = timeit.repeat(func, number=number, repeat=repeat)
    return min(times) / number * 1e6


def pinocchio_aba(
    params: UvmsParameters,
) -> Callable[[np.ndarray, np.ndarray, np.ndarray], object] | None:
    """Pinocchio's ABA for the same rigid bodies, or None if pin is not installed."""
    try:
        import pinocchio as pin
    except ImportError:
        return None
    model = pin.Model()
    model.gravity = pin.Motion(np.array([0.0, 0.0, params.hydrodynamics.gravity_m_s2, 0, 0, 0]))
    veh = params.vehicle
    root = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), 'base')
    model.appendBodyToJoint(
        root,
        pin.Inertia(veh.mass_kg, np.array(veh.center_of_gravity_m), np.diag(veh.inertia_kg_m2)),
        pin.SE3.Identity(),
    )
    arm = params.arm
    axes = np.array(arm.joint_axes).reshape(3, 3)
    parent, placement = root, np.array(arm.mount_position_m)
    for i in range(3):
        length, radius, mass = arm.link_lengths_m[i], arm.link_radii_m[i], arm.link_masses_kg[i]
        joint = model.addJoint(
            parent,
            pin.JointModelRevoluteUnaligned(axes[i]),
            pin.SE3(np.eye(3), placement),
            f'joint_{i + 1}',
        )
        model.appendBodyToJoint(
            joint,
            pin.Inertia(
                mass, np.array([0.5 * length, 0.0, 0.0]), cylinder_inertia(mass, length, radius)
            ),
            pin.SE3.Identity(),
        )
        parent, placement = joint, np.array([length, 0.0, 0.0])
    data = model.createData()

    def aba(q: np.ndarray, w: np.ndarray, tau: np.ndarray) -> object:
        quat = pin.Quaternion(rot_ned_from_body(q[3], q[4], q[5])).coeffs()
        return pin.aba(model, data, np.concatenate((q[:3], quat, q[6:])), w, tau)

    return aba


def main() -> None:
    """Time the model's calls and print a table."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument('--repeat', type=int, default=40, help='rounds per figure (best kept)')
    parser.add_argument('--number', type=int, default=300, help='calls per round')
    args = parser.parse_args()

    params = UvmsParameters()
    model = UvmsModel(params)
    rng = np.random.default_rng(0)
    q = np.concatenate((rng.uniform(-1, 1, 3), [0.1, -0.2, 0.7], [0.0, 0.93, -1.57]))
    w = rng.normal(0.0, 0.3, 9)
    tau_b = rng.normal(0.0, 20.0, 9)
    f_ee = np.array([-150.0, 0.0, 5.0])
    q_dot = model.velocity_transform(q) @ w
    dt = 1e-3
    # Two states with different joint angles: alternating defeats the per-configuration cache,
    # as in the stages of an RK4 step or one simulator step after another.
    q_other = q + np.concatenate((np.zeros(6), [0.01, -0.02, 0.03]))
    states = [q, q_other]
    counter = [0]

    def alternate() -> np.ndarray:
        counter[0] ^= 1
        return states[counter[0]]

    calls: list[tuple[str, Callable[[], object]]] = [
        ('mass_matrix_body M_b(q)', lambda: model.mass_matrix_body(alternate())),
        ('bias_body C_b w + D_b w + G_b', lambda: model.bias_body(alternate(), w)),
        ('forward_dynamics w_dot', lambda: model.forward_dynamics(alternate(), w, tau_b, f_ee)),
        ('step RK4', lambda: model.step(q, w, tau_b, f_ee, dt)),
        (
            'step semi-implicit Euler',
            lambda: model.step(alternate(), w, tau_b, f_ee, dt, method='semi_implicit_euler'),
        ),
        ('mass_matrix M(q) (eq. 18) [cached q]', lambda: model.mass_matrix(q)),
        ('bias zeta(q, q_dot) (eq. 19) [cached q]', lambda: model.bias(q, q_dot)),
        ('ee_jacobian J (eq. 22) [cached q]', lambda: model.ee_jacobian(q)),
        ('ee_jacobian_dot_qdot (eq. 23) [cached q]', lambda: model.ee_jacobian_dot_qdot(q, q_dot)),
        (
            'controller set: M, zeta, J, J_dot q_dot, X',
            lambda: (
                model.mass_matrix(alternate()),
                model.bias(states[counter[0]], q_dot),
                model.ee_jacobian(states[counter[0]]),
                model.ee_jacobian_dot_qdot(states[counter[0]], q_dot),
                model.ee_position(states[counter[0]]),
            ),
        ),
    ]
    print(
        f'uvms_model benchmark: Python {platform.python_version()}, numpy {np.__version__}, '
        f'{platform.machine()}; best of {args.repeat} x {args.number} calls'
    )
    results: dict[str, float] = {}
    for name, func in calls:
        results[name] = per_call_us(func, args.number, args.repeat)
        print(f'  {name:<42s} {results[name]:9.1f} us')

    aba = pinocchio_aba(params)
    step_us = results['step RK4']
    if aba is None:
        print('  pinocchio not installed: no ABA reference')
    else:
        aba_us = per_call_us(lambda: aba(q, w, tau_b), args.number, args.repeat)
        print(f'  {"pinocchio aba (rigid bodies, C++)":<42s} {aba_us:9.1f} us')
        print(
            f'  forward_dynamics / aba: {results["forward_dynamics w_dot"] / aba_us:6.1f}x; '
            f'RK4 step / (4 aba): {step_us / (4 * aba_us):6.1f}x'
        )
    verdict = 'met' if step_us <= TARGET_STEP_US else 'MISSED'
    stretch = 'met' if step_us <= STRETCH_STEP_US else 'not met'
    print(
        f'  RK4 step {step_us:.1f} us: target {TARGET_STEP_US:.0f} us {verdict}, '
        f'stretch {STRETCH_STEP_US:.0f} us {stretch}'
    )


if __name__ == '__main__':
    main()
